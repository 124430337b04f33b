"""What a report's prose says about its results, tied to the run that renders it.

A literate report (the notebooks in ``notebooks/``) explains its results in
sentences, and a sentence that quotes a number, a comparison or a verdict
goes stale the moment a re-render changes the result under it: nothing
compares prose with outputs. Here a sentence about a computed result takes
one of two forms:

- **Rendered from the result.** :func:`say` turns text built from the
  computed values (an f-string) into Markdown shown as the cell's output:
  the sentence changes with the numbers. :func:`either` picks between two
  wordings by a computed condition, for a sentence whose words, not only its
  numbers, depend on the run (``"holds the truth"`` or ``"misses it"``).
- **Literal, and checked.** A sentence left in a Markdown cell states a
  fact of the results below it; :func:`claim` checks that fact in the code
  cell beside it and stops the render with a :class:`ClaimError` that quotes
  the sentence when a run no longer supports it. Use it for a sentence
  whose wording a number cannot carry ("iis is best at every budget"), and
  :func:`claim_near` for a rounded number quoted in prose ("about 0.09").

Numbers quoted from the thesis are not results of the run: they stay literal
and say where they come from ("the thesis reports IC 0.92", "thesis Figure
3.5").

Examples
--------
>>> from dynia.claims import claim, claim_near, either, say
>>> best = {"uniform": 0.13, "iis": 0.08}
>>> claim(best["iis"] < best["uniform"], "iis ends closer to the reference than uniform sampling")
>>> claim_near(0.0871, 0.09, "the noise floor's sigma, about 0.09", digits=2)
>>> print(say(f"iis ends at {best['iis']:.2f}, {either(best['iis'] < 0.1, 'below', 'above')} 0.1.").data)
iis ends at 0.08, below 0.1.
>>> claim(best["iis"] > best["uniform"], "iis is worse than uniform sampling")
Traceback (most recent call last):
...
dynia.claims.ClaimError: the report says "iis is worse than uniform sampling", and this run's results do not support it
"""

import math
import textwrap

import numpy as np

from .errors import DyniaError

__all__ = ["ClaimError", "claim", "claim_near", "either", "say"]


class ClaimError(DyniaError, AssertionError):
    """A sentence of a report that the run rendering it no longer supports; the message quotes the sentence."""


def claim(holds, sentence):
    """Check that ``sentence``, which the report's prose states, holds for this run's results.

    Parameters
    ----------
    holds : bool
        The computed fact the sentence rests on, e.g. ``ratio > 3``.
    sentence : str
        The sentence (or the part of it) as the prose states it, quoted by
        the error.

    Raises
    ------
    ClaimError
        If ``holds`` is false. A numpy bool is taken as a bool; anything
        else that is not a bool is refused, so that an array or a number
        passed by mistake cannot pass by being non-empty or non-zero.

    Examples
    --------
    >>> claim(3 > 2, "three exceeds two")
    """
    _require_bool(holds, f"claim of {sentence!r}")
    if not holds:
        raise ClaimError(f'the report says "{sentence}", and this run\'s results do not support it')


def claim_near(value, quoted, sentence, *, digits=None, rel=None):
    """Check that a number the prose quotes, ``quoted``, is this run's ``value`` as the prose rounds it.

    Parameters
    ----------
    value : float
        The computed number.
    quoted : float
        The number as the sentence writes it.
    sentence : str
        The sentence, quoted by the error.
    digits : int, optional
        The prose rounds to this many decimals: ``value`` must round to
        ``quoted``.
    rel : float, optional
        Instead, the prose says "about": ``value`` must lie within this
        relative distance of ``quoted``.

    Raises
    ------
    ClaimError
        If the number is not what the sentence says (or is not finite).

    Examples
    --------
    >>> claim_near(18.93, 18.9, "gains from about 18.9", digits=1)
    >>> claim_near(3.2, 3, "about three times", rel=0.2)
    """
    if (digits is None) == (rel is None):
        raise TypeError("claim_near needs one of digits= (the prose rounds) or rel= (the prose says about)")
    value = float(value)
    if digits is not None:
        holds = math.isfinite(value) and round(value, digits) == round(float(quoted), digits)
    else:
        holds = math.isfinite(value) and abs(value - quoted) <= rel * abs(quoted)
    if not holds:
        raise ClaimError(
            f'the report says "{sentence}" ({quoted:g}), and this run gives {value:g}, which it does not support'
        )


def either(condition, if_true, if_false):
    """``if_true`` or ``if_false`` by a computed ``condition``: the words of a sentence that depend on the run.

    Examples
    --------
    >>> either(0.4 < 0.5, "below", "above")
    'below'
    """
    _require_bool(condition, f"either({if_true!r}, {if_false!r})")
    return if_true if condition else if_false


def _require_bool(value, what):
    """Refuse anything but a bool (numpy's included): an array or a number would pass by being non-empty."""
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(f"the {what} needs a bool; got {type(value).__name__}")


def say(text):
    """Markdown of a sentence or paragraph built from computed values, shown as the cell's output.

    The text is dedented and stripped, so that a triple-quoted f-string can
    be indented with the code. Returns an ``IPython.display.Markdown`` (the
    last expression of a notebook cell is displayed; ``.data`` holds the
    text), or the text itself where IPython is not installed.

    Examples
    --------
    >>> say(f'''
    ...     IC peaks at {0.912:.2f}.
    ... ''').data
    'IC peaks at 0.91.'
    """
    text = textwrap.dedent(text).strip()
    try:
        from IPython.display import Markdown
    except ImportError:
        return text
    return Markdown(text)
