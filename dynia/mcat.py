"""``dynia.mcat``: the same module object as :mod:`dynia.reference.mcat`, under its short name.

``import dynia.mcat`` and ``from dynia import mcat`` give :mod:`dynia.reference.mcat` itself, not a copy.
"""

import sys

from .reference import mcat

sys.modules[__name__] = mcat
