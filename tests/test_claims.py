"""dynia.claims: a report's sentence that its run no longer supports stops the render, naming the sentence."""

import numpy as np
import pytest

from dynia.claims import ClaimError, claim, claim_near, either, say
from dynia.errors import DyniaError


def test_a_claim_that_holds_passes_and_one_that_fails_quotes_its_sentence():
    claim(np.float64(0.4) < 0.5, "IC stays below 0.5")
    with pytest.raises(ClaimError, match='says "IC stays below 0.5"'):
        claim(np.float64(0.6) < 0.5, "IC stays below 0.5")


def test_a_failed_claim_is_an_assertion_and_a_dynia_error():
    with pytest.raises(AssertionError):
        claim(False, "anything")
    with pytest.raises(DyniaError):
        claim(False, "anything")


@pytest.mark.parametrize("value", [np.array([True, False]), 1, 0.0, "yes", None])
def test_a_claim_refuses_anything_but_a_bool(value):
    with pytest.raises(TypeError, match="needs a bool"):
        claim(value, "a sentence")


def test_a_rounded_number_must_round_to_what_the_prose_writes():
    claim_near(0.0894, 0.09, "sigma 0.09", digits=2)
    with pytest.raises(ClaimError, match=r"\(0.09\), and this run gives 0.0949"):
        claim_near(0.0949, 0.09, "sigma 0.09", digits=3)
    with pytest.raises(ClaimError):
        claim_near(np.nan, 0.09, "sigma 0.09", digits=2)


def test_about_is_a_relative_distance():
    claim_near(4.1, 4, "about four times", rel=0.1)
    with pytest.raises(ClaimError):
        claim_near(4.1, 3, "about three times", rel=0.2)
    with pytest.raises(TypeError, match="one of digits"):
        claim_near(4.1, 3, "about three times")


def test_either_picks_the_words_by_a_computed_condition():
    assert either(np.bool_(True), "holds", "misses") == "holds"
    assert either(False, "holds", "misses") == "misses"
    with pytest.raises(TypeError):
        either(np.array([1.0]), "holds", "misses")


def test_say_renders_dedented_markdown():
    shown = say(f"""
        IC peaks at {0.9123:.2f}
        on day {12}.
    """)
    assert shown.data == "IC peaks at 0.91\non day 12."
    assert shown._repr_markdown_() == shown.data
