"""Plain reference implementations, kept as the oracles the engine is tested against.

:mod:`~dynia.reference.thesis` is the one-to-one port of the thesis's MATLAB
(Appendix B); :mod:`~dynia.reference.mcat` ports the DYNIA of the MCAT
toolbox (``id_time.m``). Both are slow on purpose: loops as written.
"""

from . import mcat, thesis

__all__ = ["mcat", "thesis"]
