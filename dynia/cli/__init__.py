"""The ``dynia`` command: ``dynia analyse``, ``dynia identify`` and ``dynia suggest`` on logged data.

:func:`main` is the entry point. :mod:`~dynia.cli.parser` makes the options
(those of the analysis from the fields of
:class:`~dynia.settings.AnalysisSettings`); :mod:`~dynia.cli.commands` runs
them on the library; :mod:`~dynia.cli.report` writes the tables,
``summary.json`` and the printed verdicts; :mod:`~dynia.cli.figures` draws
the figures. The commands and the library load only once a command is to
run, so ``dynia --version`` and ``dynia analyse --help`` answer at once.
"""

import signal
import sys
import warnings

import numpy as np

from ..errors import DyniaError, Interrupted
from .parser import attached, parser

__all__ = ["main"]


def main(argv=None):
    """Entry point of the ``dynia`` command; returns the exit status.

    Errors in what the user gave (a :class:`~dynia.errors.DyniaError`) end
    the command with one line on stderr and status 2; a signal with status
    128 + its number and nothing written. Any other exception is a bug in
    dynia and keeps its traceback.
    """
    command_parser = parser()
    command_line = ["dynia", *(sys.argv[1:] if argv is None else map(str, argv))]
    try:
        # Warnings of numpy, matplotlib and the rest would break the promise of
        # one line per error; dynia's own warnings are reported by the commands.
        with warnings.catch_warnings(record=True) as caught, np.errstate(all="ignore"):
            warnings.simplefilter("always")
            args = command_parser.parse_args(attached(command_parser, command_line[1:]))
            if args.command is None:
                command_parser.print_help()
                return 2
            from . import commands

            return commands.execute(args, command_line, caught)
    except DyniaError as error:
        print(f"dynia: error: {' '.join(str(error).split())}", file=sys.stderr)
        return 2
    except Interrupted as error:
        print(f"dynia: {error}; nothing was written", file=sys.stderr)
        return 128 + getattr(signal, error.signal_name)
    except KeyboardInterrupt:
        print("dynia: interrupted; nothing was written", file=sys.stderr)
        return 130
