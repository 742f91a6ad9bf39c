"""The `fatswarm run` command (flags, summary, resume) and `fatswarm algorithms`."""
