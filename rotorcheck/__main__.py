"""``python -m rotorcheck`` runs the command line."""

from rotorcheck.cli import run

run()
