"""Secured swarms: identities and access control on paper, and the certificates that enforce it."""
