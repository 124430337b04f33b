"""Checkpoints of an online analysis: its whole state as bytes, without its model's code, and back.

:meth:`dynia.online.OnlineDynia.to_bytes` writes the state of an analysis
with :func:`state_bytes`: pickled, with its model left out (whoever restores
the state gives the model again, so that no code travels with the bytes).
:meth:`~dynia.online.OnlineDynia.from_bytes` reads it with
:func:`restored_state`, which rebuilds the classes of numpy's arrays and of
dynia's own models, settings, flavours and online analysis only: bytes
naming any other (a damaged or foreign checkpoint) raise a
:class:`~dynia.errors.DataError` instead of running code. A series of
checkpoints (``dynia follow``'s) writes its large arrays once, in
:class:`SharedArrays`.
"""

import io
import pickle

import numpy as np

from .errors import DataError, ModelError

__all__ = ["SharedArrays", "state_bytes", "restored_state"]


def state_bytes(state, model, shared=None):
    """``state`` (an online analysis) as bytes, ``model`` left out and the arrays of ``shared`` referred to.

    Parameters
    ----------
    state : dynia.online.OnlineDynia
    model : dynia.models.Model
        The model ``state`` simulates, stored as a reference.
    shared : SharedArrays, optional
        Arrays of a series of checkpoints that are written once: every
        array of the state that equals one of them is stored as a
        reference to it. An empty one takes every large array of this state.

    Raises
    ------
    ModelError
        Something of the state cannot be pickled (a model's stepper holding
        what is not a numpy array or a plain value).
    """
    buffer = io.BytesIO()
    pickler = pickle.Pickler(buffer, protocol=pickle.HIGHEST_PROTOCOL)
    if shared is None or shared.accepting:

        def persistent_id(value):
            if value is model:
                return _MODEL_ID
            return None if shared is None else shared.reference(value)

    else:
        # Called for every object pickled: a dict look-up of the shared arrays checked beforehand.
        references = shared.unchanged()

        def persistent_id(value):
            return _MODEL_ID if value is model else references.get(id(value))

    pickler.persistent_id = persistent_id
    try:
        pickler.dump(state)
    except (pickle.PicklingError, TypeError, AttributeError) as error:  # what pickle raises varies by object
        raise ModelError(
            f"the state of {model!r}'s simulation cannot be saved: {error}; a checkpoint holds numpy "
            "arrays and plain values (a model's own functions are taken from the model itself)"
        ) from None
    if shared is not None:
        shared.accepting = False
    return buffer.getvalue()


def restored_state(data, model, shared=None):
    """The object :func:`state_bytes` gave ``data`` of, with ``model`` and the ``shared`` arrays it was written with.

    Raises
    ------
    DataError
        ``data`` names a class that is not numpy's or dynia's own, or a
        reference that neither ``model`` nor ``shared`` holds, or cannot be
        read at all.
    """
    unpickler = _StateUnpickler(io.BytesIO(data))

    def load(key):
        if key == _MODEL_ID:
            return model
        if shared is not None and key in shared.arrays:
            return shared.copy(key)
        return _refuse_state(f"reference {key!r}")

    unpickler.persistent_load = load
    try:
        state = unpickler.load()
    except DataError:
        raise
    except Exception as error:  # what a damaged pickle raises varies: truncated, bad opcode, bad arguments
        raise DataError(f"the saved OnlineDynia state cannot be read ({type(error).__name__}: {error})") from None
    return state


class SharedArrays:
    """The large arrays that a series of :meth:`dynia.online.OnlineDynia.to_bytes` checkpoints share, written once.

    The first checkpoint written with an empty one takes every array of at
    least :attr:`SMALLEST` bytes; later ones refer to each that still equals
    it (compared byte for byte: an array changed in place is written out
    again) and write the others in full.

    Attributes
    ----------
    arrays : dict of str to ndarray
        The shared arrays by key, as first written.
    """

    SMALLEST = 1024

    def __init__(self, arrays=None):
        self.arrays = dict(arrays or {})
        self.accepting = not self.arrays
        self._keys = {}  # id of an array of the state -> its key
        self._bytes = {}  # key -> the shared array's bytes, to compare with
        self._holders = {}  # key -> the array of the state that held it when last seen

    def reference(self, value):
        """The key of ``value`` when it is a shared array, else None (a persistent id of pickle)."""
        if not isinstance(value, np.ndarray) or value.nbytes < self.SMALLEST:
            return None
        key = self._keys.get(id(value))
        # A read-only array (the samples) cannot have changed in place: no comparison needed.
        if key is not None and (not value.flags.writeable or self._same(value, key)):
            return key
        if not self.accepting:
            return None
        key = f"a{len(self.arrays)}"
        self.arrays[key] = value.copy()
        self._keys[id(value)] = key
        self._holders[key] = value
        return key

    def unchanged(self):
        """{id: key} of the arrays of the state that still hold their shared array (see :meth:`reference`)."""
        return {
            id(value): key
            for key, value in self._holders.items()
            if not value.flags.writeable or self._same(value, key)
        }

    def _same(self, value, key):
        """Whether ``value`` holds shared array ``key`` byte for byte (NaN payloads and signed zeros included)."""
        kept = self.arrays[key]
        if value.dtype != kept.dtype or value.shape != kept.shape:
            return False
        if key not in self._bytes:
            self._bytes[key] = kept.tobytes()
        return value.tobytes() == self._bytes[key]

    def copy(self, key):
        """A copy of shared array ``key`` for a restored state, remembered as that array."""
        value = self.arrays[key].copy()
        self._keys[id(value)] = key
        self._holders[key] = value
        return value

    def to_bytes(self):
        buffer = io.BytesIO()
        np.savez(buffer, **self.arrays)
        return buffer.getvalue()

    @classmethod
    def from_bytes(cls, data):
        try:
            with np.load(io.BytesIO(data), allow_pickle=False) as stored:
                return cls({key: stored[key] for key in stored.files})
        except Exception as error:  # a damaged archive: zipfile's, numpy's or the OS's error
            raise DataError(f"the saved shared arrays cannot be read ({type(error).__name__}: {error})") from None


# Where the model was in the state of to_bytes: the restorer gives it back.
_MODEL_ID = "model"

# What a saved state may rebuild besides dynia's own classes: numpy's arrays, dtypes and scalars.
_NUMPY_REBUILDERS = frozenset(
    {
        ("numpy", "dtype"),
        ("numpy", "ndarray"),
        *(
            (f"numpy.{core}.{module}", name)
            for core in ("core", "_core")
            for module, name in (("numeric", "_frombuffer"), ("multiarray", "_reconstruct"), ("multiarray", "scalar"))
        ),
    }
)

# The modules of the classes an OnlineDynia holds: its flavour, its settings, the model's stepper.
_STATE_MODULES = ("dynia.online", "dynia.settings", "dynia.engine.flavours", "dynia.models.")


def _refuse_state(what):
    raise DataError(f"the saved OnlineDynia state names {what}, which no state written by to_bytes holds")


class _StateUnpickler(pickle.Unpickler):
    """Rebuilds numpy arrays and the classes of dynia's own state, nothing else (see :func:`restored_state`)."""

    def find_class(self, module, name):
        if (module, name) in _NUMPY_REBUILDERS:
            return super().find_class(module, name)
        if module.startswith(_STATE_MODULES) or module == "dynia.models":
            found = super().find_class(module, name)
            if isinstance(found, type):
                return found
        return _refuse_state(f"{module}.{name}")
