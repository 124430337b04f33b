"""Old home of the thesis port, kept so existing imports work: see :mod:`dynia.reference.thesis`."""

from .reference.thesis import *  # noqa: F403
from .reference.thesis import __all__  # noqa: F401
