"""Old home of the MCAT port, kept so existing imports work: see :mod:`dynia.reference.mcat`."""

from .reference.mcat import *  # noqa: F403
from .reference.mcat import __all__  # noqa: F401
