"""Old home of the likelihood and CLD arithmetic, kept so existing imports work: see :mod:`dynia.engine.cld`."""

from .engine.cld import *  # noqa: F403
from .engine.cld import __all__  # noqa: F401
