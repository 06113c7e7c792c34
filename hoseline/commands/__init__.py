"""Sub-commands of the hoseline command line that live outside cli.py; each registers on cli.app."""
