"""The ``dynia`` command: ``dynia analyse``, ``dynia identify`` and ``dynia suggest`` on logged data.

:mod:`~dynia.cli.commands` parses the command line and runs the library;
:mod:`~dynia.cli.report` writes the tables, ``summary.json`` and the printed
verdicts; :mod:`~dynia.cli.figures` draws the figures.
"""

from .commands import main

__all__ = ["main"]
