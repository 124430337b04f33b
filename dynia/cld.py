"""Deprecated: the old home of the likelihood and CLD arithmetic; import from :mod:`dynia.engine.cld`.

Importing this module raises a :class:`DeprecationWarning`; it will be removed
in dynia 0.3.0.
"""

import warnings

from .engine.cld import *  # noqa: F403
from .engine.cld import __all__  # noqa: F401

warnings.warn(
    "dynia.cld is deprecated and will be removed in dynia 0.3.0: import from dynia.engine.cld",
    DeprecationWarning,
    stacklevel=2,
)
