"""Output folders that never cost a user a file: checked first, written whole or not at all.

The rules (every command that writes follows them):

* **A command replaces only what the same command wrote.** A folder this package wrote carries
  the marker file ``.vo_lib_output.json`` (which command wrote it, and the names it wrote) and
  holds nothing else. ``run`` replaces only a folder whose marker says ``vo_lib run``,
  ``generate`` only a generated sequence (``vo_lib generate``, or a sample sequence written
  before markers existed, known by its ``manifest.json``; the command line asks for ``--force``
  there too, as a sequence may be in use), ``sweep NAME`` only a sweep of the
  same experiment, which it resumes. A new or empty folder may always be written. Any other
  folder is refused with :class:`OutputError`, in one line naming what is there, unless the
  caller passes ``force``; even then a folder is never replaced if it is, holds or lies inside
  the command's input, or if it is or holds the current folder, the home folder, the sample data
  folder or this package. A sequence that a running command reads is never replaced: the
  reader holds a shared lock on it (:func:`reading`), and a replacement needs it exclusively.
* **Atomic.** Everything is written into a temporary sibling, ``.NAME.vo_lib-PID-HOST-<random>.tmp``,
  renamed to ``NAME`` when complete; the folder it replaces is removed only after that. A failed
  or interrupted write removes its temporary folder (the command line turns SIGINT and SIGTERM
  into exceptions so that this happens), and a temporary folder left by a process that no longer
  runs (killed, power cut) is removed by the next write beside it, with a notice.
* **Permissions follow the umask**, for folders as for files.

The parts: :func:`check_target` (may this folder be written?), :class:`OutputFolder` (a folder
written whole; ``checksums=True`` records every file's checksum, so that a file edited or added
there since keeps the folder from being replaced), :func:`claim_folder` (a folder kept and
updated over many runs, such as a build folder with its caches), :func:`swap_in` (a finished
folder renamed into place), :func:`writing` and :func:`reading` (the locks), :func:`write_atomic`,
:func:`read_marker`, :func:`remove_stale_temporaries`, :func:`notice` and :class:`OutputError`.
"""

from __future__ import annotations

import contextlib
import errno
import hashlib
import json
import os
import re
import shutil
import socket
import sys
import tempfile
import threading
from pathlib import Path

#: Set by the command line's Ctrl-C handler. Python raises KeyboardInterrupt where the signal
#: lands, but inside a callback from compiled code (Numba compiling its cache) the exception is
#: only reported and dropped; the flag keeps the interrupt, so that no output is committed.
INTERRUPTED = threading.Event()

MARKER = ".vo_lib_output.json"
#: What a sample sequence written before markers existed holds (its ``manifest.json`` names the sample).
_LEGACY_SEQUENCE = {
    "image_0",
    "image_1",
    "calib.txt",
    "times.txt",
    "poses.txt",
    "odometry.txt",
    "manifest.json",
}
#: The command whose old output (no marker) is known by its contents: a sample's manifest.
_LEGACY_WRITER = "vo_lib generate"
_FRAME_FILE = re.compile(r"\d+\.png")
_TEMPORARY = re.compile(r"\..+\.vo_lib-(\d+)-([0-9a-f]{8})-[^/]*\.(?:tmp|old)")


#: The contents a marker of :func:`claim_folder` lists: whatever the command keeps there.
ANY_CONTENTS = "*"


class OutputError(ValueError):
    """An output folder that may not be written (it holds files this package did not write)."""


def notice(message: str) -> None:
    """One line on stderr for something the user should know that is not an error."""
    print(f"notice: {message}", file=sys.stderr)


def _host() -> str:
    return hashlib.sha1(socket.gethostname().encode()).hexdigest()[:8]


def _temporary_prefix(name: str) -> str:
    return f".{name}.vo_lib-{os.getpid()}-{_host()}-"


def umask() -> int:
    """The process's umask, read without changing it where the system allows."""
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _contains(outer: Path, inner: Path) -> bool:
    """``outer`` is ``inner`` or one of its parents."""
    return outer == inner or outer in inner.parents


def _describe(folder: Path) -> str:
    files = folders = size = 0
    for root, dirs, names in os.walk(folder):
        folders += len(dirs)
        files += len(names)
        for name in names:
            try:
                size += os.lstat(os.path.join(root, name)).st_size
            except OSError:
                pass
    amount = f"{size / 1e6:.1f} MB" if size >= 1e5 else f"{size / 1e3:.1f} kB"
    return f"{files} file{'s' * (files != 1)} in {folders + 1} folder{'s' * (folders > 0)}, {amount}"


def file_checksums(folder) -> dict[str, str]:
    """sha256 of every file under ``folder`` but the marker, by path relative to it."""
    folder = Path(folder)
    return {
        p.relative_to(folder).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(folder.rglob("*"))
        if p.is_file() and p.name != MARKER
    }


def _owned_names(folder: Path, has_marker: bool, written_by: str) -> set[str] | str | None:
    """The names ``written_by`` wrote into ``folder`` by its marker (or, for a sample sequence
    from before markers, by its manifest); a string saying why the folder is not its own; None
    when the marker's checksums show every file as written."""
    if has_marker:
        try:
            data = json.loads((folder / MARKER).read_text(encoding="utf-8"))
            contents = data["contents"]
            contents = ANY_CONTENTS if contents == ANY_CONTENTS else set(contents)
            writer = str(data["written_by"])
            files = data.get("files")
            if files is not None and not isinstance(files, dict):
                raise TypeError("files is not a mapping")
        except (OSError, ValueError, KeyError, TypeError, AttributeError):
            return f"its marker {MARKER} is damaged"
        if writer != written_by:
            return f"it holds the output of `{writer}`, which `{written_by}` does not replace"
        if files is not None:
            now = file_checksums(folder)
            changed = sorted(k for k in files.keys() | now.keys() if files.get(k) != now.get(k))
            return f"{changed[0]} was added, changed or removed since it was written" if changed else None
        return contents
    try:
        manifest = json.loads((folder / "manifest.json").read_text(encoding="utf-8"))
        legacy = isinstance(manifest, dict) and {"sample", "fingerprint"} <= manifest.keys()
    except (OSError, ValueError):
        legacy = False
    if legacy and written_by == _LEGACY_WRITER:
        return _LEGACY_SEQUENCE
    return "it was not written by this program"


def foreign_content(folder: Path, written_by: str) -> str | None:
    """None if ``folder`` is empty or holds only what the command ``written_by`` wrote there;
    else why not, in a few words."""
    try:
        entries = {e.name: e for e in os.scandir(folder)}
    except OSError as exc:
        return f"cannot be listed ({exc.strerror or exc})"
    if not entries:
        return None
    contents = _owned_names(folder, MARKER in entries, written_by)
    if contents is None or contents == ANY_CONTENTS:  # checksums match, or a claimed folder
        return None
    if isinstance(contents, str):
        return contents
    for name, entry in sorted(entries.items()):
        if name == MARKER:
            continue
        if name not in contents:
            return f"it holds {name}, which this program did not write"
        if entry.is_dir(follow_symlinks=False):
            for inner in os.scandir(entry.path):
                if not (inner.is_file(follow_symlinks=False) and _FRAME_FILE.fullmatch(inner.name)):
                    return f"it holds {name}/{inner.name}, which this program did not write"
    return None


def _check_inputs(real: Path, inputs, label: str) -> None:
    """``real`` is none of ``inputs``, above none and inside none."""
    for given in inputs:
        source = Path(given).resolve()
        if real == source:
            raise OutputError(f"{label}: is the input sequence; choose another output folder")
        if _contains(real, source):
            raise OutputError(f"{label}: holds the input sequence {source}; choose another output folder")
        if _contains(source, real):
            raise OutputError(
                f"{label}: lies inside the input sequence {source}; choose another output folder"
            )


def _check_guarded(real: Path, keep: dict | None, label: str) -> None:
    """``real`` is not and holds neither this package, the current or home folder, nor ``keep``."""
    guarded = {Path(__file__).resolve().parent: "this package"}
    for where, what in ((Path.cwd, "the current folder"), (Path.home, "your home folder")):
        try:
            guarded[where().resolve()] = what
        except (OSError, RuntimeError):  # no current folder (deleted) or no home
            pass
    for folder, what in (keep or {}).items():
        guarded.setdefault(Path(folder).resolve(), what)
    for folder, what in guarded.items():
        if _contains(real, folder):
            is_or_holds = "is" if real == folder else "holds"
            raise OutputError(f"{label}: {is_or_holds} {what}; choose another output folder")


def check_target(
    target,
    *,
    written_by: str,
    force: bool = False,
    inputs=(),
    keep: dict | None = None,
    option: str | None = None,
) -> str | None:
    """Raise :class:`OutputError` unless folder ``target`` may be (re)written by ``written_by``.

    ``inputs`` are folders read by the command: ``target`` may not be one of them, above one, or
    inside one. ``keep`` maps folders never replaced, even with ``force``, to what they are (the
    current folder, the home folder and this package are always among them). Returns, when
    ``force`` replaces a folder that is not ``written_by``'s own, what is replaced (path, size
    and why); otherwise None.
    """
    label = f"{option} {target}" if option else str(target)
    path = Path(target)
    if path.is_symlink() and not path.exists():
        raise OutputError(f"{label}: a symbolic link to {os.readlink(path)}, which does not exist")
    real = path.resolve()
    _check_inputs(real, inputs, label)
    _check_guarded(real, keep, label)
    if not real.exists():
        above = real.parent
        while not above.exists() and above != above.parent:
            above = above.parent
        if not above.is_dir():
            raise OutputError(f"{label}: cannot write there ({above} is a file)")
        return None
    if not real.is_dir():
        raise OutputError(
            f"{label}: is a file, not a folder; choose another output folder (--force replaces folders only)"
        )
    why = foreign_content(real, written_by)
    if why is None:
        return None
    if not force:
        raise OutputError(
            f"{label}: the folder exists and {why}; choose another folder, or add --force to replace it"
        )
    return f"{real} ({_describe(real)}; {why})"


def claim_folder(target, written_by: str, *, force: bool = False, option: str | None = None) -> Path:
    """Make ``target`` a folder that the command ``written_by`` keeps and updates over many runs
    (a build folder with its caches), rather than one written whole: it must be new, empty, or
    claimed by the same command before (``force`` claims any other folder, under the rules of
    :func:`check_target`). The folder is created and marked; returns its resolved path. Anything
    that prevents it (a file there, no permission, a damaged marker) is one :class:`OutputError`.
    """
    replacing = check_target(target, written_by=written_by, force=force, option=option)
    label = f"{option} {target}" if option else str(target)
    real = Path(target).resolve()
    try:
        real.mkdir(parents=True, exist_ok=True)
        marker = {"written_by": written_by, "contents": ANY_CONTENTS}
        write_atomic(real / MARKER, json.dumps(marker, indent=2, sort_keys=True) + "\n")
    except OSError as exc:
        raise OutputError(f"{label}: cannot write there ({exc.strerror or exc})") from None
    if replacing:
        notice(f"--force: claimed {replacing}; what it holds may be overwritten")
    return real


@contextlib.contextmanager
def reading(folder):
    """Hold a shared lock on ``folder`` while a command reads it: no command replaces it meanwhile
    (:class:`OutputFolder` needs the lock exclusively). Where folders cannot be locked (Windows, or
    a file system without locks) nothing is held."""
    fd = _lock(Path(folder), shared=True)
    try:
        yield
    finally:
        if fd is not None:
            os.close(fd)


@contextlib.contextmanager
def _exclusive(real: Path, target, option: str | None, doing: str = "reading"):
    """The exclusive lock on an existing folder ``real`` (nothing if it does not exist yet);
    :class:`OutputError` if a running command reads or writes it."""
    try:
        fd = _lock(real, shared=False)
    except BlockingIOError:
        label = f"{option} {target}" if option else str(target)
        raise OutputError(
            f"{label}: a running command is {doing} this folder; try again when it has finished"
        ) from None
    try:
        yield
    finally:
        if fd is not None:
            os.close(fd)


def writing(folder, option: str | None = None):
    """Hold an exclusive lock on ``folder`` while a command updates it in place (a sweep appending
    its rows): a second command that would read, write or replace it meanwhile is refused with
    :class:`OutputError`. A context manager; where folders cannot be locked nothing is held."""
    return _exclusive(Path(folder), folder, option, doing="writing to")


def _lock(folder: Path, shared: bool) -> int | None:
    """An open descriptor of ``folder`` holding a lock (BlockingIOError if held elsewhere in the
    other mode), or None where the folder is missing or cannot be locked."""
    try:
        import fcntl
    except ImportError:
        return None
    try:
        fd = os.open(folder, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
    except OSError:
        return None
    try:
        fcntl.flock(fd, (fcntl.LOCK_SH if shared else fcntl.LOCK_EX) | fcntl.LOCK_NB)
    except BlockingIOError:
        os.close(fd)
        raise
    except OSError:  # no locks on this file system
        os.close(fd)
        return None
    return fd


def remove_stale_temporaries(parent: Path) -> list[Path]:
    """Remove the temporaries (folders and files) in ``parent`` left by processes of this machine
    that no longer run; returns them."""
    removed = []
    if os.name == "nt":  # os.kill(pid, 0) would not test but stop the process there
        return removed
    try:
        entries = list(os.scandir(parent))
    except OSError:
        return removed
    host = _host()
    for entry in entries:
        match = _TEMPORARY.fullmatch(entry.name)
        if not match or match.group(2) != host or entry.is_symlink():
            continue
        if not _gone(int(match.group(1))):
            continue
        if entry.is_dir(follow_symlinks=False):
            shutil.rmtree(entry.path, ignore_errors=True)
        else:
            with contextlib.suppress(OSError):
                os.unlink(entry.path)
        if not os.path.lexists(entry.path):
            removed.append(Path(entry.path))
    return removed


def _gone(pid: int) -> bool:
    """Does process ``pid`` of this machine no longer run (and is not this one)?"""
    if pid == os.getpid():
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    except (PermissionError, OverflowError, OSError):
        return False
    return False


def write_atomic(path, text: str) -> Path:
    """Replace the file ``path`` by ``text`` through a temporary file beside it (named as the
    package's temporaries are, so that one left by a killed process is removed later); readers
    see the old file or the new one, never a part."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=_temporary_prefix(path.name), suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="") as fh:
            fh.write(text)
            fh.flush()
            os.fsync(fh.fileno())
        os.chmod(tmp, 0o666 & ~umask())
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    return path


def read_marker(folder) -> dict | None:
    """The marker of ``folder`` (which command wrote it, what it holds), or None if it has none
    or it cannot be read."""
    try:
        data = json.loads((Path(folder) / MARKER).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None


def swap_in(complete: Path, target: Path) -> None:
    """Rename ``complete`` to ``target``; an existing ``target`` is removed once that is done."""
    try:
        os.rename(complete, target)  # no target, or an empty folder
        return
    except OSError as exc:
        if exc.errno not in (errno.ENOTEMPTY, errno.EEXIST):
            raise
    aside = Path(tempfile.mkdtemp(prefix=_temporary_prefix(target.name), suffix=".old", dir=target.parent))
    os.rename(target, aside / "old")
    try:
        os.rename(complete, target)
    except BaseException:
        os.rename(aside / "old", target)
        shutil.rmtree(aside, ignore_errors=True)
        raise
    shutil.rmtree(aside, ignore_errors=True)


class OutputFolder:
    """A folder written whole: checked on entry, filled in :attr:`path` (a temporary sibling), put
    in place by :meth:`commit`; on any exception (or without a commit) nothing is left behind.
    With ``checksums`` the marker records every file's sha256, and the folder is replaced later
    only while every file is as written (no file added, edited or removed).

    ::

        with OutputFolder("runs/x", "vo_lib run", inputs=[sequence_path]) as out:
            (out.path / "poses.txt").write_text(...)
            out.commit(seed=0)
    """

    def __init__(
        self, target, written_by: str, *, force=False, inputs=(), keep=None, option=None, checksums=False
    ):
        self.target = Path(target)
        self.written_by = written_by
        self.checksums = checksums
        self.committed = False
        self._check = dict(written_by=written_by, force=force, inputs=tuple(inputs), keep=keep, option=option)
        self.replacing = check_target(self.target, **self._check)
        self.real = self.target.resolve()
        with _exclusive(self.real, self.target, option):  # fail now, not after the work
            pass
        self._created: list[Path] = []
        above = self.real.parent
        while not above.exists():
            self._created.insert(0, above)
            above = above.parent
        label = f"{option} {target}" if option else str(target)
        try:
            for folder in self._created:
                folder.mkdir()
            stale = remove_stale_temporaries(self.real.parent)
            if stale:
                names = ", ".join(p.name for p in stale)
                notice(f"removed {len(stale)} temporary folder(s) left by interrupted runs: {names}")
            self.path = Path(
                tempfile.mkdtemp(
                    prefix=_temporary_prefix(self.real.name), suffix=".tmp", dir=self.real.parent
                )
            )
            os.chmod(self.path, 0o777 & ~umask())
        except OSError as exc:
            self._remove_created()
            raise OutputError(f"{label}: cannot write there ({exc.strerror or exc})") from None

    def commit(self, **details) -> Path:
        """Mark the folder as ours, check the target again (it may have changed meanwhile) and
        rename the folder into place; returns the target.

        An interrupt that arrived while compiled code held the interpreter (and so was swallowed,
        see :data:`INTERRUPTED`) is raised here, before anything is put in place."""
        if INTERRUPTED.is_set():
            raise KeyboardInterrupt
        names = sorted(p.name for p in self.path.iterdir())
        marker = {"written_by": self.written_by, "contents": names, **details}
        if self.checksums:
            marker["files"] = file_checksums(self.path)
        (self.path / MARKER).write_text(json.dumps(marker, indent=2, sort_keys=True) + "\n", encoding="utf-8")
        replacing = check_target(self.target, **self._check)
        with _exclusive(self.real, self.target, option=self._check["option"]):
            swap_in(self.path, self.real)
        self.committed = True
        if replacing:
            notice(f"--force: replaced {replacing}")
        return self.target

    def discard(self) -> None:
        if not self.committed:
            shutil.rmtree(self.path, ignore_errors=True)
            self._remove_created()

    def _remove_created(self) -> None:
        for folder in reversed(self._created):
            try:
                folder.rmdir()  # only if still empty
            except OSError:
                break
        self._created = []

    def __enter__(self) -> OutputFolder:
        return self

    def __exit__(self, exc_type, exc, tb) -> bool:
        self.discard()
        return False
