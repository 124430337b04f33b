"""Models DYNIA simulates: the built-in linear ones, and any model you bring.

:mod:`~dynia.models.base` defines what a model offers (:class:`Model`: batched
simulation of many parameter sets, streamed in time chunks) and the shape
convention every model follows; :mod:`~dynia.models.linear` the exact
zero-order-hold linear models (:class:`FirstOrder`, :class:`FOPDT`,
:class:`SecondOrderDelay`), and :mod:`~dynia.models.transfer` any
python-control model simulated the same way (:class:`TransferFunction`);
:mod:`~dynia.models.custom` wraps your own simulator (:class:`FunctionModel`)
or state update (:class:`StateSpaceModel`).
:mod:`~dynia.models.conceptual` holds nonlinear conceptual models built on
them (HYMOD, a draining tank), loaded on first use.

Examples
--------
>>> import numpy as np
>>> from dynia.models import FOPDT
>>> model = FOPDT()
>>> model.names
('K', 'T', 'theta')
>>> params = np.array([[2.0, 1.0, 0.0], [2.0, 1.0, 1.5]])
>>> model.simulate(params, np.ones(4)).round(3)
array([[0.   , 1.264, 1.729, 1.9  ],
       [0.   , 0.   , 0.787, 1.554]])
"""

import importlib

from .base import Model, SimulationState
from .custom import FunctionModel, StateSpaceModel
from .linear import FOPDT, FirstOrder, LinearModel, SecondOrderDelay
from .transfer import TransferFunction

__all__ = [
    "Model",
    "SimulationState",
    "LinearModel",
    "FirstOrder",
    "FOPDT",
    "SecondOrderDelay",
    "TransferFunction",
    "FunctionModel",
    "StateSpaceModel",
]


def __getattr__(name):
    # The conceptual models (HYMOD, a tank) load on first use: dynia.models.conceptual.hymod().
    if name == "conceptual":
        return importlib.import_module(f"{__name__}.conceptual")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
