"""``python -m dynia.cli``: the ``dynia`` command without its console script."""

import sys

from . import main

sys.exit(main())
