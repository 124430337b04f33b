"""Skips for conditions of the environment the tests run in, not of the code under test."""

import signal

import pytest


def skip_if_signal_ignored(name):
    """Skip a test that delivers signal ``name`` when this process inherited it ignored.

    Under ``nohup`` SIGHUP is ignored, and in a shell's background job SIGINT is; a child
    inherits that, and dynia deliberately leaves an ignored signal ignored, so the signal
    never arrives as an interrupt and the test would fail for a reason not in the code.
    """
    if signal.getsignal(getattr(signal, name)) is signal.SIG_IGN:
        pytest.skip(f"{name} is ignored in this process (nohup or a background job), so a child cannot receive it")
