"""Where a run's results go, and the rules that keep the user's own files safe.

:class:`OutputDirectory` gives the caller an empty staging directory beside ``out`` and moves it to ``out`` only
when the caller finishes without an exception. The rules:

1. ``out`` must be a directory or not exist yet: a file, a symlink or anything else is refused and never deleted.
2. An existing ``out`` is refused unless ``--overwrite`` is given.
3. ``--overwrite`` replaces only a directory dynia created and that holds nothing else: one holding the marker file
   ``.dynia-output`` (JSON: dynia's version, the command, the time of creation, and ``files``, the path and size
   of every file dynia wrote, and ``directories``), which dynia writes into every result directory, and no file or
   directory the marker does not list, nor a listed file whose size changed. Anything else is named in the error
   and the directory is left alone, so a marker echoed into a folder, or copied with results into one that holds
   a thesis, does not make the other files deletable; a marker without ``files`` (written by hand, or by an
   earlier dynia that did not record them) covers no file at all.
4. Always refused, even with ``--overwrite``: an ``out`` that is an input file or contains one, that is the current
   directory or one of its parents, or that is the filesystem root, the home directory or a parent of it. Paths
   are compared after resolving ``..`` and symlinks.
5. Before any work starts, ``out``'s parent is created if needed and the staging directory ``.NAME.partial-XXXX``
   is made in it, so an unwritable location fails at once. The staging directories that runs killed outright
   (SIGKILL, the out-of-memory killer, ``os._exit``) left there are removed first: holding the lock, no live run
   has one.
6. One run at a time per ``out``: a second run fails at once while the lock file ``.NAME.dynia-lock`` beside
   ``out`` is held.
7. If ``out`` appears while dynia works (or, with ``--overwrite``, stops being dynia's), it is left alone and the
   new results are kept beside it as ``NAME.dynia-YYYYmmdd-HHMMSS``; the error says where. An old ``out`` is moved
   aside before the new one takes its place and deleted only after that.
8. SIGTERM and SIGHUP during the run raise :class:`~dynia.errors.Interrupted`, SIGINT raises ``KeyboardInterrupt``;
   then, as on any other error, the staging directory is removed, ``out`` is left as it was and the lock is
   released. A signal the process ignores (as under ``nohup``) stays ignored.
9. Results get the permissions the umask allows (``0o777 & ~umask`` for directories, ``0o666 & ~umask`` for
   files) rather than the owner-only ``0o700`` of a temporary directory.

Examples
--------
>>> import pathlib, shutil, tempfile
>>> from dynia.io.outdir import OutputDirectory
>>> out = pathlib.Path(tempfile.mkdtemp()) / "results"
>>> with OutputDirectory(out, command="analyse") as staging:
...     _ = (staging / "ic.csv").write_text("time,k\\n")
>>> sorted(path.name for path in out.iterdir())
['.dynia-output', 'ic.csv']
>>> shutil.rmtree(out.parent)
"""

import datetime
import fcntl
import json
import os
import shutil
import signal
import stat
import tempfile
import threading
from glob import escape as glob_escape
from pathlib import Path

from ..errors import Interrupted, OutputError

__all__ = ["OutputDirectory", "MARKER"]

MARKER = ".dynia-output"
_SIGNALS = ("SIGINT", "SIGTERM", "SIGHUP")


def _umask():
    """The process's umask, read without changing it where Linux allows."""
    try:
        with open("/proc/self/status") as status:
            for line in status:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except OSError:
        pass
    # Elsewhere the umask can only be read by setting it and setting it back. A thread creating a file in between
    # gets 0o077, so at worst a file too private, never one too open; this happens once, before any work.
    mask = os.umask(0o077)
    os.umask(mask)
    return mask


def _inside(path, directory):
    """Whether resolved ``path`` is resolved ``directory`` or lies below it."""
    return os.path.commonpath([path, directory]) == directory


# How many foreign entries an error names before it only counts the rest.
_LISTED = 5


def _marker(path):
    """The marker record of directory ``path`` if it is a real directory holding dynia's marker; else None."""
    marker = os.path.join(path, MARKER)
    try:
        if not (stat.S_ISDIR(os.lstat(path).st_mode) and stat.S_ISREG(os.lstat(marker).st_mode)):
            return None
        with open(marker) as file:
            record = json.load(file)
    except (OSError, ValueError):  # unreadable or not JSON
        return None
    return record if isinstance(record, dict) and record.get("created_by") == "dynia" else None


def _contents(path):
    """Every entry below ``path`` but the marker: {relative path: size} for files, None for anything else."""
    found = {}
    for root, directories, names in os.walk(path):
        for name in directories + names:
            entry = os.path.join(root, name)
            relative = os.path.relpath(entry, path)
            if relative == MARKER:
                continue
            mode = os.lstat(entry).st_mode
            found[relative] = os.lstat(entry).st_size if stat.S_ISREG(mode) else ("dir" if stat.S_ISDIR(mode) else None)
    return found


def _foreign(path):
    """What in directory ``path`` dynia did not write, as its marker records: a list of relative paths.

    None when ``path`` holds no valid marker. A file of a listed name whose size changed counts as foreign, and so
    does a symlink or anything but a regular file or directory.
    """
    record = _marker(path)
    if record is None:
        return None
    files = record.get("files")
    files = files if isinstance(files, dict) else {}
    directories = record.get("directories")
    directories = set(directories) if isinstance(directories, list) else set()
    foreign = []
    try:
        contents = _contents(path)
    except OSError:  # a subdirectory that cannot be read: nothing in it can be vouched for
        return [path]
    for relative, size in sorted(contents.items()):
        if size == "dir" and relative in directories:
            continue
        if isinstance(size, int) and not isinstance(files.get(relative), bool) and files.get(relative) == size:
            continue
        foreign.append(relative)
    return foreign


def _made_by_dynia(path):
    """Whether ``path`` is a real directory holding dynia's marker and nothing dynia did not write."""
    return _foreign(path) == []


def _remove_dead_staging(parent, name):
    """Remove the staging directories of earlier runs for ``out`` that died without cleaning up (SIGKILL, os._exit).

    Called holding ``out``'s lock, which a live run holds until it has cleaned up: any ``.NAME.partial-*`` there
    now is a dead run's. Only a real directory that holds dynia's marker (written first into every staging
    directory) or nothing at all is removed; anything else of that name is left alone.
    """
    for entry in parent.glob(f".{glob_escape(name)}.partial-*"):
        try:
            if _marker(entry) is not None or (entry.is_dir() and not entry.is_symlink() and not any(entry.iterdir())):
                shutil.rmtree(entry)
        except OSError:  # another user's, or read-only: left for whoever can remove it
            continue


def _named(entries):
    shown = ", ".join(entries[:_LISTED])
    return shown if len(entries) <= _LISTED else f"{shown} and {len(entries) - _LISTED} more"


class OutputDirectory:
    """A result directory written whole or not at all, never in place of something dynia did not write.

    Parameters
    ----------
    out : str or path-like
        The directory the results should end up in.
    overwrite : bool
        Replace an existing ``out`` that holds the results of an earlier dynia run.
    inputs : sequence of str or path-like
        The files the run reads; ``out`` must neither be one of them nor contain one.
    command : str, optional
        The command recorded in the marker file, for example ``"analyse"``.

    Raises
    ------
    OutputError
        At once for an ``out`` that rules 1 to 4 refuse; on entering, for an unwritable location or a run already
        writing ``out``; on leaving, when ``out`` changed during the run (the message says where the results are).

    Examples
    --------
    >>> import os
    >>> from dynia.errors import OutputError
    >>> try:
    ...     OutputDirectory(os.getcwd())
    ... except OutputError as error:
    ...     print("refused:", "current directory" in str(error))
    refused: True
    """

    def __init__(self, out, *, overwrite=False, inputs=(), command=None):
        if isinstance(inputs, (str, os.PathLike)):
            inputs = (inputs,)
        self.out = Path(out)
        self.overwrite = bool(overwrite)
        self.command = command
        self.staging = None
        # Parents resolved now (a later chdir changes nothing), the last part kept as given: a symlink there is
        # out itself, which rule 1 must see.
        name = self.out.name
        if name in ("", ".."):
            self._path = Path(os.path.realpath(out))
        else:
            self._path = Path(os.path.realpath(self.out.parent)) / name
        self._inputs = [os.path.realpath(path) for path in inputs]
        self._umask = _umask()
        self._pid = os.getpid()
        self._lock = None
        self._existed = self._staged = self._closing = False
        self._previous = {}
        self._pending = None
        self._check()

    def _check(self):
        """Refuse an ``out`` that rules 1 to 4 forbid; return whether it exists (as dynia's, to be replaced)."""
        path, shown = os.path.realpath(self._path), f"--out {self.out}"
        if path == os.sep or _inside(os.path.realpath(os.path.expanduser("~")), path):
            raise OutputError(
                f"{shown} is the filesystem root, the home directory or a parent of it; choose a new directory"
            )
        for source in self._inputs:
            if _inside(source, path):
                raise OutputError(
                    f"{shown} is or contains the input {source}; choose a directory apart from the inputs"
                )
        if _inside(os.path.realpath(os.getcwd()), path):
            raise OutputError(f"{shown} is the current directory or one of its parents; choose a new directory")
        try:
            mode = os.lstat(self._path).st_mode
        except OSError:  # absent, or in a place that cannot be read: __enter__ reports the latter
            return False
        if not stat.S_ISDIR(mode):
            raise OutputError(f"{shown} exists and is not a directory; dynia never replaces it, choose another path")
        if not self.overwrite:
            raise OutputError(f"{shown} exists; choose another directory or add --overwrite")
        foreign = _foreign(path)
        if foreign is None:
            raise OutputError(
                f"{shown} exists but dynia did not create it (it has no {MARKER} file); "
                "--overwrite replaces only dynia's own results, choose another directory"
            )
        if foreign:
            raise OutputError(
                f"{shown} holds what dynia did not write ({_named(foreign)}; not listed in its {MARKER}, "
                "or changed since); --overwrite replaces only dynia's own results: move those away or choose "
                "another directory"
            )
        return True

    def __enter__(self):
        parent, name = self._path.parent, self._path.name
        try:
            parent.mkdir(parents=True, exist_ok=True)
            self._lock = self._acquire(parent / f".{name}.dynia-lock")
            _remove_dead_staging(parent, name)
            self._existed = self._check()  # again, now that no other run can change out
            self.staging = Path(tempfile.mkdtemp(prefix=f".{name}.partial-", dir=parent))
            self._staged = True
            self._write_marker()
            self._install_handlers()
        except BaseException as error:
            self._cleanup()
            self._restore_handlers()
            if isinstance(error, OSError):
                message = f"--out {self.out}: cannot create or write in the directory {parent} ({error})"
                raise OutputError(message) from None
            raise
        return self.staging

    def __exit__(self, kind, error, traceback):
        if os.getpid() != self._pid:
            return False  # a process forked in the block and leaving it must not touch the parent's staging
        try:
            self._closing = True  # from here a signal waits until out and the lock are settled
            if kind is None:
                self._commit()
        finally:
            self._closing = True
            self._cleanup()
            self._restore_handlers()
        if self._pending is not None:
            raise KeyboardInterrupt if self._pending == "SIGINT" else Interrupted(self._pending)
        return False

    def _acquire(self, path):
        """Open and lock ``path``; fail at once if another run holds it."""
        while True:
            descriptor = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
            try:
                fcntl.flock(descriptor, fcntl.LOCK_EX | fcntl.LOCK_NB)
                if os.path.samestat(os.fstat(descriptor), os.stat(path)):
                    return descriptor, path
            except BlockingIOError:
                os.close(descriptor)
                raise OutputError(
                    f"another dynia run is writing --out {self.out} (it holds {path}); "
                    "wait for it to finish or choose another directory"
                ) from None
            except FileNotFoundError:
                pass
            except BaseException:
                os.close(descriptor)
                raise
            # The run before ours removed the lock file between our open and our lock: lock the new file instead.
            os.close(descriptor)

    def _write_marker(self, contents=None):
        """The marker file; ``contents`` (from :func:`_contents`) records what dynia wrote, when finished."""
        from .. import __version__

        record = dict(
            created_by="dynia",
            version=__version__,
            command=self.command,
            created=datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        )
        if contents is not None:
            record.update(
                files={name: size for name, size in contents.items() if isinstance(size, int)},
                directories=sorted(name for name, size in contents.items() if size == "dir"),
            )
        (self.staging / MARKER).write_text(json.dumps(record, indent=2) + "\n")

    def _install_handlers(self):
        if threading.current_thread() is not threading.main_thread():
            return  # only the main thread may set handlers; errors and KeyboardInterrupt still clean up
        for name in _SIGNALS:
            number = getattr(signal, name, None)
            previous = None if number is None else signal.getsignal(number)
            # Leave ignored signals ignored (nohup) and a SIGINT handler the caller chose.
            if previous in (None, signal.SIG_IGN) or (name == "SIGINT" and previous is not signal.default_int_handler):
                continue
            self._previous[number] = previous
            signal.signal(number, self._on_signal)

    def _on_signal(self, number, frame):
        if os.getpid() != self._pid:  # a process forked in the block (a worker pool) handles it as before
            signal.signal(number, self._previous[number])
            os.kill(os.getpid(), number)
            return
        name = signal.Signals(number).name
        if self._closing:
            self._pending = self._pending or name
            return
        raise KeyboardInterrupt if name == "SIGINT" else Interrupted(name)

    def _restore_handlers(self):
        for number, previous in self._previous.items():
            signal.signal(number, previous)
        self._previous = {}

    def _commit(self):
        """Move the finished staging directory to ``out`` (rule 7), or keep it beside ``out`` and raise."""
        self._write_marker(_contents(self.staging))  # what dynia wrote, so that a later --overwrite may replace it
        self._set_permissions()
        path = self._path
        if self._existed and not _made_by_dynia(path):
            self._keep_aside(
                f"--out {self.out} changed while dynia ran and no longer holds dynia's results; left it as it is"
            )
        if not self._existed and os.path.lexists(path):
            self._keep_aside(f"--out {self.out} appeared while dynia ran; left it as it is")
        retired = None
        if self._existed:
            try:
                retired = Path(tempfile.mkdtemp(prefix=f".{path.name}.old-", dir=path.parent))
                os.replace(path, retired / path.name)
            except OSError as error:
                if retired is not None:
                    retired.rmdir()
                self._keep_aside(f"cannot move the old --out {self.out} aside ({error.strerror}); left it as it is")
        try:
            # Replaces nothing but an empty directory made in the instant since the check above.
            os.replace(self.staging, path)
        except OSError as error:
            old = f"; the previous results are in {retired / path.name}" if retired else ""
            self._keep_aside(f"cannot move the results to --out {self.out} ({error.strerror}){old}")
        self._staged = False
        if retired is not None:
            try:
                shutil.rmtree(retired)
            except OSError as error:
                raise OutputError(
                    f"wrote --out {self.out}, but cannot remove the previous results, moved to "
                    f"{retired}: {error.strerror}"
                ) from None

    def _keep_aside(self, reason):
        """Move the finished results to a new visible name beside ``out`` and raise, saying where they are."""
        stamp = datetime.datetime.now().strftime("%Y%m%d-%H%M%S")
        attempt = 1
        while True:
            kept = self._path.parent / f"{self._path.name}.dynia-{stamp}{'' if attempt == 1 else f'-{attempt}'}"
            try:
                os.mkdir(kept)  # takes the name atomically, so nobody else's directory is replaced below
                break
            except FileExistsError:
                attempt += 1
        os.replace(self.staging, kept)
        self._staged = False
        raise OutputError(f"{reason}; the new results are in {kept}")

    def _set_permissions(self):
        directories, files = 0o777 & ~self._umask, 0o666 & ~self._umask
        os.chmod(self.staging, directories)
        for root, subdirectories, names in os.walk(self.staging):
            for name in subdirectories + names:
                entry = os.path.join(root, name)
                mode = os.lstat(entry).st_mode
                if stat.S_ISDIR(mode):
                    os.chmod(entry, directories)
                elif stat.S_ISREG(mode):  # symlinks are skipped: chmod would change what they point to
                    os.chmod(entry, files)

    def _cleanup(self):
        """Remove the staging directory unless it was moved, then unlock (and remove the lock file while locked)."""
        if self._staged:
            shutil.rmtree(self.staging, ignore_errors=True)
            self._staged = False
        if self._lock is not None:
            descriptor, path = self._lock
            self._lock = None
            try:
                os.unlink(path)
            except OSError:
                pass
            os.close(descriptor)
