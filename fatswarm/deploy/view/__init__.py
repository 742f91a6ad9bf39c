"""What a person sees: the terminal dashboard and its canvas, replays of records, plots."""
