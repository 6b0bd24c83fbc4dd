"""Subcommands of `lmsbench`: one module each, with `register(subparsers)`."""
