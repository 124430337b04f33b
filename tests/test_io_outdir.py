"""dynia.io.outdir: results are written whole or not at all, and never in place of the user's own files."""

import datetime
import json
import os
import re
import signal
import stat
import subprocess
import sys
import threading
from pathlib import Path

import pytest
from skips import skip_if_signal_ignored

import dynia
from dynia.errors import OutputError
from dynia.io.outdir import MARKER, OutputDirectory


@pytest.fixture(autouse=True)
def place(tmp_path, monkeypatch):
    """Work in an empty directory; the home directory is its sibling (child processes may write there)."""
    (tmp_path / "place").mkdir()
    monkeypatch.chdir(tmp_path / "place")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    return tmp_path / "place"


def tree(root):
    """Every entry below ``root``: its kind, bytes or link target, and permission bits."""
    entries = {}
    for folder, subfolders, names in os.walk(root):
        for name in subfolders + names:
            path = os.path.join(folder, name)
            info = os.lstat(path)
            if stat.S_ISLNK(info.st_mode):
                content = ("link", os.readlink(path))
            elif stat.S_ISREG(info.st_mode):
                content = ("file", Path(path).read_bytes())
            else:
                content = (stat.S_IFMT(info.st_mode),)
            entries[os.path.relpath(path, root)] = content + (stat.S_IMODE(info.st_mode),)
    return entries


def earlier_run(out, text="old"):
    """A directory of results as an earlier dynia run left it."""
    with OutputDirectory(out, command="analyse") as staging:
        (staging / "ic.csv").write_text(text)
        (staging / "only_old.csv").write_text("x")


def run_child(code, *args, cwd):
    return subprocess.run([sys.executable, "-c", code, *args], cwd=cwd, capture_output=True, text=True, timeout=120)


def test_clean_run_moves_the_results_into_place(place):
    real = Path(os.path.realpath(place))
    with OutputDirectory("results", command="analyse") as staging:
        assert staging.parent == real and staging.name.startswith(".results.partial-") and staging.is_dir()
        assert sorted(os.listdir()) == [".results.dynia-lock", staging.name]
        (staging / "ic.csv").write_text("time,k\n0,1\n")
        (staging / "second_run").mkdir()
        (staging / "second_run" / "ic.csv").write_text("2")
    assert os.listdir() == ["results"]
    assert sorted(os.listdir("results")) == [MARKER, "ic.csv", "second_run"]
    assert Path("results/ic.csv").read_text() == "time,k\n0,1\n"
    assert Path("results/second_run/ic.csv").read_text() == "2"
    record = json.loads(Path("results", MARKER).read_text())
    assert (record["created_by"], record["version"], record["command"]) == ("dynia", dynia.__version__, "analyse")
    age = datetime.datetime.now(datetime.timezone.utc) - datetime.datetime.fromisoformat(record["created"])
    assert datetime.timedelta(0) <= age < datetime.timedelta(minutes=1)


@pytest.mark.parametrize("existing", [False, True])
def test_an_error_in_the_block_removes_staging_and_leaves_out_alone(place, existing):
    if existing:
        earlier_run("results")
    before = tree(place)
    handlers = {number: signal.getsignal(number) for number in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)}
    with pytest.raises(RuntimeError, match="boom"):
        with OutputDirectory("results", overwrite=True) as staging:
            (staging / "ic.csv").write_text("new")
            raise RuntimeError("boom")
    assert tree(place) == before
    assert {number: signal.getsignal(number) for number in handlers} == handlers


@pytest.mark.parametrize("kind", ["file", "symlink to dynia results", "symlink to file", "dangling symlink", "fifo"])
@pytest.mark.parametrize("overwrite", [False, True])
def test_out_that_is_not_a_directory_is_refused_and_kept(place, kind, overwrite):
    Path("data.csv").write_bytes(b"precious\x00bytes\n")
    earlier_run("store")
    if kind == "file":
        Path("results").write_bytes(b"mine\n")
    elif kind == "fifo":
        os.mkfifo("results")
    else:
        target = {"symlink to dynia results": "store", "symlink to file": "data.csv", "dangling symlink": "gone"}
        os.symlink(target[kind], "results")
    before = tree(place)
    with pytest.raises(OutputError, match=r"^--out results exists and is not a directory; dynia never replaces it"):
        OutputDirectory("results", overwrite=overwrite)
    assert tree(place) == before


def test_existing_directory_needs_overwrite(place):
    earlier_run("results")
    Path("mine").mkdir()
    Path("mine/notes.txt").write_text("keep me")
    before = tree(place)
    for out in ("results", "mine"):
        with pytest.raises(OutputError) as caught:
            OutputDirectory(out)
        assert str(caught.value) == f"--out {out} exists; choose another directory or add --overwrite"
    assert tree(place) == before


@pytest.mark.parametrize("marker", ["none", "empty", "directory", "not json", "json list", "other tool", "symlink"])
def test_overwrite_refuses_a_directory_dynia_did_not_create(place, marker):
    earlier_run("store")
    Path("results").mkdir()
    Path("results/thesis.tex").write_text("years of work")
    contents = {"empty": "", "not json": "{", "json list": '["dynia"]', "other tool": '{"created_by": "other"}'}
    if marker in contents:
        Path("results", MARKER).write_text(contents[marker])
    elif marker == "directory":
        Path("results", MARKER).mkdir()
    elif marker == "symlink":
        os.symlink(os.path.abspath(Path("store", MARKER)), Path("results", MARKER))
    before = tree(place)
    with pytest.raises(OutputError, match=rf"^--out results exists but dynia did not create it \(it has no {MARKER}"):
        OutputDirectory("results", overwrite=True)
    assert tree(place) == before


def test_overwrite_replaces_an_earlier_run_completely(place):
    earlier_run("results", text="old")
    with OutputDirectory("results", overwrite=True, command="identify") as staging:
        assert Path("results/ic.csv").read_text() == "old"  # the old results stay until the new ones are done
        (staging / "ic.csv").write_text("new")
    assert os.listdir() == ["results"]  # no retired copy, staging or lock file left behind
    assert sorted(os.listdir("results")) == [MARKER, "ic.csv"]
    assert Path("results/ic.csv").read_text() == "new"
    assert json.loads(Path("results", MARKER).read_text())["command"] == "identify"


def test_failed_final_rename_keeps_both_old_and_new_results(place, monkeypatch):
    earlier_run("results", text="old")
    out = os.path.realpath("results")
    real_replace = os.replace

    def replace(source, target):
        if os.fspath(target) == out and ".partial-" in os.fspath(source):
            raise OSError(18, "Invalid cross-device link")
        return real_replace(source, target)

    with pytest.raises(OutputError) as caught:
        with OutputDirectory("results", overwrite=True) as staging:
            (staging / "ic.csv").write_text("new")
            monkeypatch.setattr(os, "replace", replace)
    message = str(caught.value)
    kept = re.search(r"the new results are in (\S+)$", message).group(1)
    old = re.search(r"the previous results are in (\S+);", message).group(1)
    assert message.startswith("cannot move the results to --out results (Invalid cross-device link)")
    assert Path(kept, "ic.csv").read_text() == "new" and Path(old, "ic.csv").read_text() == "old"
    assert not Path("results").exists()


@pytest.mark.parametrize("how", ["same file", "contains", "contains, given through ..", "through a symlink"])
def test_out_that_is_or_contains_an_input_is_refused(place, how):
    earlier_run("results")
    Path("results/data.csv").write_text("t,y\n0,1\n")
    Path("results/sub").mkdir()
    os.symlink(os.path.realpath("results"), "link")
    out, inputs = {
        "same file": ("results/data.csv", ["results/data.csv"]),
        "contains": ("results", ["results/data.csv"]),
        "contains, given through ..": ("results/sub/..", ["results/data.csv"]),
        "through a symlink": ("results", ["link/data.csv"]),
    }[how]
    before = tree(place)
    with pytest.raises(OutputError, match=rf"^--out {out} is or contains the input .*data\.csv; choose a directory"):
        OutputDirectory(out, overwrite=True, inputs=inputs)
    assert tree(place) == before


def test_a_single_input_path_is_not_split_into_characters(place):
    Path("data.csv").write_text("t,y\n")
    with pytest.raises(OutputError, match="is or contains the input"):
        OutputDirectory("data.csv", overwrite=True, inputs="data.csv")


@pytest.mark.parametrize("out", [".", "..", "sub/..", "{cwd}", "{link}"])
def test_current_directory_and_its_parents_are_refused(place, monkeypatch, out):
    monkeypatch.setenv("HOME", "/nonexistent/home")  # so that only the rule on the current directory applies
    earlier_run("work")
    Path("work/sub").mkdir()
    os.symlink("work", "link")
    monkeypatch.chdir("work")
    out = out.format(cwd=os.getcwd(), link=place / "link" / "sub" / "..")
    before = tree(place)
    with pytest.raises(OutputError, match=rf"^--out {re.escape(out)} is the current directory or one of its parents"):
        OutputDirectory(out, overwrite=True)
    assert tree(place) == before


@pytest.mark.parametrize("out", ["/", "{home}", "{home}/../home", "{tmp}"])
def test_root_and_home_are_refused(place, out):
    home = Path(os.environ["HOME"])
    home.mkdir()
    (home / MARKER).write_text('{"created_by": "dynia"}')  # as if dynia made it: only the home rule applies
    out = out.format(home=home, tmp=home.parent)
    before = tree(home.parent)
    with pytest.raises(OutputError, match=rf"^--out {re.escape(out)} is the filesystem root, the home directory"):
        OutputDirectory(out, overwrite=True)
    assert tree(home.parent) == before


def test_out_is_checked_again_on_entering(place):
    directory = OutputDirectory("results")
    Path("results").mkdir()
    Path("results/theirs.txt").write_text("theirs")
    before = tree(place)
    with pytest.raises(OutputError, match="^--out results exists; choose another directory or add --overwrite$"):
        with directory:
            pytest.fail("the block must not run")
    assert tree(place) == before  # neither a staging directory nor the lock file is left


def test_missing_parents_are_created_before_the_work_starts(place):
    with OutputDirectory("a/b/c/results") as staging:
        assert Path("a/b/c").is_dir() and staging.parent == Path(os.path.realpath("a/b/c"))
        assert staging.name.startswith(".results.partial-")
        (staging / "ic.csv").write_text("x")
    assert sorted(os.listdir("a/b/c")) == ["results"]
    assert Path("a/b/c/results/ic.csv").read_text() == "x"


def test_parent_that_is_a_file_fails_on_entering(place):
    Path("notes").write_text("mine")
    before = tree(place)
    started = []
    with pytest.raises(OutputError, match=r"^--out notes/results: cannot create or write in the directory .*notes "):
        with OutputDirectory("notes/results"):
            started.append(True)
    assert not started and tree(place) == before


@pytest.mark.skipif(os.geteuid() == 0, reason="root may write into a read-only directory")
def test_unwritable_parent_fails_on_entering(place):
    Path("locked").mkdir()
    os.chmod("locked", 0o555)
    started = []
    try:
        with pytest.raises(
            OutputError,
            match=r"^--out locked/results: cannot create or write in the directory "
            r"\S*locked \(\[Errno 13\]",
        ):
            with OutputDirectory("locked/results"):
                started.append(True)
        assert not started and os.listdir("locked") == []
    finally:
        os.chmod("locked", 0o755)


@pytest.mark.skipif(os.geteuid() != 0 or not os.path.isdir("/sys"), reason="needs root and sysfs")
def test_unwritable_parent_fails_on_entering_even_for_root():
    with pytest.raises(
        OutputError,
        match=r"^--out /sys/dynia-outdir-test: cannot create or write in the directory "
        r"/sys \(",
    ):
        with OutputDirectory("/sys/dynia-outdir-test"):
            pytest.fail("the block must not run")
    assert not os.path.lexists("/sys/dynia-outdir-test")


def test_second_run_on_the_same_out_fails_fast_and_loses_nothing(place):
    with OutputDirectory("results") as staging:
        (staging / "ic.csv").write_text("first")
        for _ in range(2):  # the failed attempt must leave the first run's lock in force
            second = OutputDirectory("results")
            with pytest.raises(OutputError) as caught:
                with second:
                    pytest.fail("the block must not run")
            assert str(caught.value).startswith("another dynia run is writing --out results (it holds ")
        assert sorted(os.listdir()) == [".results.dynia-lock", staging.name]
    assert os.listdir() == ["results"]
    assert Path("results/ic.csv").read_text() == "first"


HOLDER = """
import sys
from dynia.io.outdir import OutputDirectory
with OutputDirectory("results") as staging:
    (staging / "ic.csv").write_text("child")
    print("ready", flush=True)
    sys.stdin.readline()
"""


def test_run_in_another_process_holds_the_lock(place):
    child = subprocess.Popen(
        [sys.executable, "-c", HOLDER], cwd=place, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True
    )
    try:
        assert child.stdout.readline() == "ready\n"
        with pytest.raises(OutputError, match="^another dynia run is writing --out results"):
            with OutputDirectory("results"):
                pytest.fail("the block must not run")
    finally:
        child.communicate("\n", timeout=60)
    assert child.returncode == 0
    assert os.listdir() == ["results"] and Path("results/ic.csv").read_text() == "child"


def test_lock_file_left_by_a_killed_run_does_not_block(place):
    Path(".results.dynia-lock").write_text("")
    with OutputDirectory("results") as staging:
        (staging / "ic.csv").write_text("x")
    assert os.listdir() == ["results"]


@pytest.mark.parametrize("appears", ["empty directory", "directory", "file"])
def test_out_appearing_during_the_run_is_kept_and_results_go_beside_it(place, appears):
    with pytest.raises(OutputError) as caught:
        with OutputDirectory("results") as staging:
            (staging / "ic.csv").write_text("new")
            if appears == "file":
                Path("results").write_text("theirs")
            else:
                Path("results").mkdir()
                if appears == "directory":
                    Path("results/theirs.txt").write_text("theirs")
    mine = tree(place)
    kept = [name for name in os.listdir() if name.startswith("results.dynia-")]
    assert len(kept) == 1 and re.fullmatch(r"results\.dynia-\d{8}-\d{6}", kept[0])
    assert str(caught.value) == (
        f"--out results appeared while dynia ran; left it as it is; the new results are in {os.path.realpath(kept[0])}"
    )
    assert sorted(os.listdir(kept[0])) == [MARKER, "ic.csv"] and Path(kept[0], "ic.csv").read_text() == "new"
    expected = {"file": {"results"}, "empty directory": {"results"}, "directory": {"results", "results/theirs.txt"}}
    assert {name for name in mine if not name.startswith("results.dynia-")} == expected[appears]
    if appears != "empty directory":
        assert (Path("results") if appears == "file" else Path("results/theirs.txt")).read_text() == "theirs"


@pytest.mark.parametrize("change", ["marker removed", "replaced by the user's directory", "replaced by a file"])
def test_out_no_longer_dynias_at_the_rename_is_kept(place, change):
    earlier_run("results")
    with pytest.raises(
        OutputError,
        match=r"^--out results changed while dynia ran and no longer holds dynia's results;"
        r" left it as it is; the new results are in \S+results\.dynia-\d{8}-\d{6}$",
    ):
        with OutputDirectory("results", overwrite=True) as staging:
            (staging / "ic.csv").write_text("new")
            if change == "marker removed":
                os.remove(Path("results", MARKER))
            else:
                os.rename("results", "moved")
                if change == "replaced by a file":
                    Path("results").write_text("theirs")
                else:
                    Path("results").mkdir()
                    Path("results/theirs.txt").write_text("theirs")
    if change == "marker removed":
        assert sorted(os.listdir("results")) == ["ic.csv", "only_old.csv"]
        assert Path("results/ic.csv").read_text() == "old"
    elif change == "replaced by a file":
        assert Path("results").read_text() == "theirs"
    else:
        assert os.listdir("results") == ["theirs.txt"]


def test_kept_results_never_take_an_existing_name(place):
    now = datetime.datetime.now()
    taken = [f"results.dynia-{(now + datetime.timedelta(seconds=step)).strftime('%Y%m%d-%H%M%S')}" for step in range(4)]
    for name in taken:
        Path(name).mkdir()
    Path(taken[0], "theirs.txt").write_text("theirs")  # the others stay empty: os.replace would take them over
    before = tree(place)
    with pytest.raises(OutputError) as caught:
        with OutputDirectory("results") as staging:
            (staging / "ic.csv").write_text("new")
            Path("results").mkdir()
    kept = Path(str(caught.value).rsplit(" ", 1)[1])
    assert kept.name not in taken and (kept / "ic.csv").read_text() == "new"
    assert {name: entry for name, entry in tree(place).items() if name.split("/")[0] in taken} == {
        name: entry for name, entry in before.items() if name.split("/")[0] in taken
    }


INTERRUPTED = """
import os, signal, sys, time
from dynia.errors import Interrupted
from dynia.io.outdir import OutputDirectory
number = getattr(signal, sys.argv[1])
before = signal.getsignal(number)
try:
    with OutputDirectory("results", overwrite=True) as staging:
        (staging / "ic.csv").write_text("new")
        os.kill(os.getpid(), number)
        time.sleep(30)
    print("not interrupted")
except Interrupted as error:
    print("Interrupted", error.signal_name, signal.getsignal(number) == before)
    sys.exit(3)
except KeyboardInterrupt:
    print("KeyboardInterrupt", signal.getsignal(number) == before)
    sys.exit(4)
"""


@pytest.mark.parametrize(
    "name, status, printed",
    [
        ("SIGTERM", 3, "Interrupted SIGTERM True"),
        ("SIGHUP", 3, "Interrupted SIGHUP True"),
        ("SIGINT", 4, "KeyboardInterrupt True"),
    ],
)
@pytest.mark.parametrize("existing", [False, True])
def test_signal_in_the_block_cleans_up_and_restores_handlers(place, name, status, printed, existing):
    skip_if_signal_ignored(name)
    if existing:
        earlier_run("results")
    before = tree(place)
    child = run_child(INTERRUPTED, name, cwd=place)
    assert (child.returncode, child.stdout) == (status, printed + "\n"), child.stderr
    assert tree(place) == before  # no .partial-* directory, no lock file, out as it was


IGNORED = """
import os, signal
from dynia.io.outdir import OutputDirectory
signal.signal(signal.SIGHUP, signal.SIG_IGN)
with OutputDirectory("results") as staging:
    os.kill(os.getpid(), signal.SIGHUP)
    (staging / "ic.csv").write_text("done")
print(signal.getsignal(signal.SIGHUP) is signal.SIG_IGN)
"""


def test_an_ignored_signal_stays_ignored(place):
    child = run_child(IGNORED, cwd=place)
    assert (child.returncode, child.stdout) == (0, "True\n"), child.stderr
    assert Path("results/ic.csv").read_text() == "done"


LATE_SIGNAL = """
import os, signal, sys
from dynia.errors import Interrupted
from dynia.io.outdir import OutputDirectory
real_replace = os.replace
def replace(source, target):
    real_replace(source, target)
    os.kill(os.getpid(), signal.SIGTERM)  # arrives after every step of the final move
try:
    with OutputDirectory("results", overwrite=True) as staging:
        (staging / "ic.csv").write_text("new")
        os.replace = replace
except Interrupted as error:
    print("Interrupted", error.signal_name)
"""


def test_signal_during_the_final_move_waits_until_out_is_complete(place):
    skip_if_signal_ignored("SIGTERM")
    earlier_run("results", text="old")
    child = run_child(LATE_SIGNAL, cwd=place)
    assert (child.returncode, child.stdout) == (0, "Interrupted SIGTERM\n"), child.stderr
    assert os.listdir() == ["results"]
    assert sorted(os.listdir("results")) == [MARKER, "ic.csv"] and Path("results/ic.csv").read_text() == "new"


FORKED = """
import os, signal, sys, time
from dynia.io.outdir import OutputDirectory
with OutputDirectory("results") as staging:
    (staging / "ic.csv").write_text("parent")
    pid = os.fork()
    if pid == 0:
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(30)
        os._exit(0)
    _, killed = os.waitpid(pid, 0)
    pid = os.fork()
    if pid == 0:
        sys.exit(5)  # leaves the with-block in the child
    _, exited = os.waitpid(pid, 0)
print(os.WIFSIGNALED(killed) and os.WTERMSIG(killed) == signal.SIGTERM, os.WEXITSTATUS(exited))
"""


def test_forked_child_dies_of_the_signal_without_touching_the_run(place):
    skip_if_signal_ignored("SIGTERM")
    child = run_child(FORKED, cwd=place)
    assert (child.returncode, child.stdout) == (0, "True 5\n"), child.stderr
    assert os.listdir() == ["results"] and Path("results/ic.csv").read_text() == "parent"


def test_works_outside_the_main_thread(place):
    handlers = {number: signal.getsignal(number) for number in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)}
    failures = []

    def write():
        try:
            with OutputDirectory("results") as staging:
                (staging / "ic.csv").write_text("thread")
                failures.extend(number for number, handler in handlers.items() if signal.getsignal(number) != handler)
        except Exception as error:  # the assertion below reports it
            failures.append(error)

    thread = threading.Thread(target=write)
    thread.start()
    thread.join()
    assert failures == [] and Path("results/ic.csv").read_text() == "thread"


@pytest.mark.parametrize("umask, directory_mode, file_mode", [(0o022, 0o755, 0o644), (0o077, 0o700, 0o600)])
def test_results_get_the_permissions_the_umask_allows(place, umask, directory_mode, file_mode):
    Path("elsewhere.txt").write_text("not dynia's")
    os.chmod("elsewhere.txt", 0o640)
    previous = os.umask(umask)
    try:
        with OutputDirectory("results") as staging:
            assert stat.S_IMODE(staging.stat().st_mode) == 0o700  # private while it is being written
            (staging / "ic.csv").write_text("x")
            os.chmod(staging / "ic.csv", 0o600)
            (staging / "second_run").mkdir(mode=0o700)
            (staging / "second_run" / "limits.csv").write_text("y")
            os.symlink(os.path.realpath("elsewhere.txt"), staging / "link")
    finally:
        os.umask(previous)
    modes = {name: entry[-1] for name, entry in tree(place / "results").items() if entry[0] != "link"}
    assert stat.S_IMODE(os.stat("results").st_mode) == directory_mode
    assert modes == {
        MARKER: file_mode,
        "ic.csv": file_mode,
        "second_run": directory_mode,
        "second_run/limits.csv": file_mode,
    }
    assert stat.S_IMODE(os.stat("elsewhere.txt").st_mode) == 0o640


DIES_IN_THE_RUN = """
import os
from dynia.io.outdir import OutputDirectory
with OutputDirectory("results", command="analyse") as staging:
    (staging / "ic.csv").write_text("half")
    os._exit(9)  # as SIGKILL or the out-of-memory killer end it: no clean-up runs
"""


def test_the_next_run_removes_the_staging_directory_of_a_killed_run(place):
    """Issue 32: a run killed outright left .results.partial-* beside --out for ever."""
    assert run_child(DIES_IN_THE_RUN, cwd=place).returncode == 9
    [dead] = list(place.glob(".results.partial-*"))
    # Not dynia's: a directory of that name without dynia's marker that holds something stays.
    (place / ".results.partial-mine").mkdir()
    (place / ".results.partial-mine" / "notes.txt").write_text("keep")
    with OutputDirectory("results", command="analyse") as staging:
        assert not dead.exists()
        (staging / "ic.csv").write_text("new")
    assert sorted(path.name for path in place.glob(".results.partial-*")) == [".results.partial-mine"]
    assert (place / "results" / "ic.csv").read_text() == "new"
