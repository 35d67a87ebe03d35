"""Subcommands added by later modules register here (kept out of cli.py's core)."""
