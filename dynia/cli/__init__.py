"""The ``dynia`` command: ``dynia analyse``, ``identify``, ``suggest`` and ``follow`` on logged data.

:func:`main` is the entry point. Each command is a module:
:mod:`~dynia.cli.analyse`, :mod:`~dynia.cli.identify`,
:mod:`~dynia.cli.suggest` and :mod:`~dynia.cli.follow` hold its options
(``OPTIONS``, and ``cli_parse``, which adds them to the parser), its own
``check`` of them, the class of its typed options object (``Options``) and
its run (``cli_action``). :mod:`~dynia.cli.options` holds what the commands'
options share (those of the analysis made from the fields of
:class:`~dynia.settings.AnalysisSettings`); :mod:`~dynia.cli.common` what
their runs share; :mod:`~dynia.cli.report` writes the tables,
``summary.json`` and the printed verdicts; :mod:`~dynia.cli.figures` draws
the figures. The library loads only once a command is to run, so ``dynia
--version`` and ``dynia analyse --help`` answer at once. Bad input ends the
command with one line on stderr and exit status 2.
"""

import signal
import sys
import warnings

import numpy as np

from ..errors import DyniaError, Interrupted
from . import analyse, follow, identify, suggest
from .options import attached, named_as_options, parser

__all__ = ["main"]

# Each command's module, by the command's name, in the order of dynia --help.
COMMANDS = {"analyse": analyse, "identify": identify, "suggest": suggest, "follow": follow}


def main(argv=None):
    """Entry point of the ``dynia`` command; returns the exit status.

    Errors in what the user gave (a :class:`~dynia.errors.DyniaError`) end
    the command with one line on stderr and status 2; a signal with status
    128 + its number and nothing written. Any other exception is a bug in
    dynia and keeps its traceback.
    """
    command_parser = parser(COMMANDS.values())
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
            command = COMMANDS[args.command]
            from .common import checked_options

            with named_as_options(command.OPTIONS):
                return command.cli_action(checked_options(command, args, command_line), caught)
    except DyniaError as error:
        print(f"dynia: error: {' '.join(str(error).split())}", file=sys.stderr)
        return 2
    except Interrupted as error:
        print(f"dynia: {error}; nothing was written", file=sys.stderr)
        return 128 + getattr(signal, error.signal_name)
    except KeyboardInterrupt:
        print("dynia: interrupted; nothing was written", file=sys.stderr)
        return 130
