"""Data, options and helpers shared by the command-line tests: running dynia in-process and checking what it prints."""

import hashlib
import os
import re
import stat
from pathlib import Path

from dynia.cli import main

ROOT = Path(__file__).resolve().parent.parent
HEATING = ROOT / "data" / "heating_system" / "heating_system.csv"

# A step test of 40 rows at 1 s: the input steps at 6 s, the output at 7 s.
GOOD = "time,u,y\n" + "".join(f"{t},{1.0 if t > 5 else 0.0},{2.0 if t > 6 else 0.0}\n" for t in range(40))
BASE = (
    "--time time --input u --output y --model first-order --param K=0:5 --param T=0:5 --samples 100 --n 3 --seed 2"
).split()

# Text that must never reach the user: a traceback, a Python warning (RuntimeWarning, UserWarning, ...),
# numpy's floating-point complaints, matplotlib's chatter.
FORBIDDEN = re.compile(r"Traceback|\b\w*Warning\b|encountered in|[Mm]atplotlib|warnings\.warn")


def write_text_file(path, text):
    path.write_text(text)
    return path


def cli_run(capsys, command, *args):
    """Run ``dynia COMMAND ARGS`` in this process: (exit status, stdout, stderr)."""
    status = main([command, *map(str, args)])
    captured = capsys.readouterr()
    return status, captured.out, captured.err


def cli_analyse(capsys, *args):
    return cli_run(capsys, "analyse", *args)


def assert_clean_streams(out, err):
    """Neither stream shows a traceback or a warning of numpy, matplotlib or Python's warnings module."""
    for name, text in (("stdout", out), ("stderr", err)):
        found = FORBIDDEN.search(text)
        assert found is None, f"{name} holds {found.group()!r}:\n{text}"


def cli_succeeded(status, out, err):
    assert status == 0, err
    assert_clean_streams(out, err)
    lines = err.splitlines()
    assert all(line.startswith("dynia:") for line in lines), err


def cli_one_error(status, out, err, *needles):
    """Exit status 2 and exactly one ``dynia: error:`` line on stderr holding every needle."""
    assert status == 2, (status, err)
    assert_clean_streams(out, err)
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("dynia: error:"), err
    for needle in needles:
        assert needle in lines[0], f"{needle!r} not in {lines[0]!r}"
    return lines[0]


def tree_state(path):
    """Every file and directory at or under ``path``: bytes digest and permission bits; None if absent."""
    path = Path(path)
    if not os.path.lexists(path):
        return None

    def entry(item):
        mode = os.lstat(item).st_mode
        content = hashlib.sha256(item.read_bytes()).hexdigest() if stat.S_ISREG(mode) else stat.S_IFMT(mode)
        return content, stat.S_IMODE(mode)

    if not path.is_dir():
        return {".": entry(path)}
    return {".": entry(path)} | {str(item.relative_to(path)): entry(item) for item in sorted(path.rglob("*"))}
