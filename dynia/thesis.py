"""``dynia.thesis``: the same module object as :mod:`dynia.reference.thesis`, under its short name.

``import dynia.thesis`` and ``from dynia import thesis`` give :mod:`dynia.reference.thesis` itself, not a copy.
"""

import sys

from .reference import thesis

sys.modules[__name__] = thesis
