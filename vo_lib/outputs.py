"""Output folders that never cost a user a file: checked first, written whole or not at all.

* **A command replaces only what the same command wrote**: such a folder holds the marker
  ``.vo_lib_output.json`` (its command, every file and folder it wrote) and nothing else. New or
  empty folders may be written; any other is :class:`OutputError`, but another command's intact
  output with ``force``. Never replaced, even so: the input, this package or what lies inside them,
  and folders that are or hold the current folder, the home folder or the repository's ``data/``.
* **Atomic**: written into a temporary sibling, marker last, put in place by
  :func:`vo_lib.atomic.swap_in`; a failed or interrupted write deletes the temporary.
* **Locks**: a reader holds a shared lock (:func:`reading`); a replacement needs it exclusively.
* **Permissions follow the umask.**
"""

from __future__ import annotations

import contextlib
import fcntl
import hashlib
import itertools
import json
import os
import shutil
from pathlib import Path

from vo_lib.atomic import (
    clear_abandoned,
    inode,
    notice,
    real_path,
    remove_replaced,
    restore,
    swap_in,
    temporary,
    write_atomic,
)

#: The signals that stopped the command, as the exceptions its handlers raised: one dropped where it
#: landed (a finalizer, a callback from compiled code) still stops the commit.
INTERRUPTED: list[BaseException] = []
MARKER = ".vo_lib_output.json"
#: The contents a marker of :func:`claim_folder` lists: whatever the command keeps there.
ANY_CONTENTS = "*"
PACKAGE = Path(__file__).resolve().parent
#: Entries looked through for links under an input and the folders it links to.
MAX_WALKED = 100_000
#: The repository's sample data folder (in a checkout): never replaced, even with ``force``.
REPOSITORY_DATA = PACKAGE.parent / "data"
#: What a refusal advises, by whether ``force`` may replace the folder.
FIX_BY_FORCE = {
    True: "choose another folder, or add --force to replace it",
    False: "choose another folder: this program replaces only what it wrote",
}


class OutputError(ValueError):
    """An output folder that may not be written (it holds files this package did not write)."""


def _label(target, option: str | None) -> str:
    return f"{option} {target}" if option else str(target)


def _contains(outer: Path, inner: Path) -> bool:
    """``outer`` is ``inner`` or one of its parents, by name or by inode (a bind mount, say)."""
    same = (inode(outer) or "none") in {inode(p) for p in (inner, *inner.parents)}
    return outer == inner or outer in inner.parents or same


def file_sha256(path) -> str:
    """The sha256 of the file ``path``, in hex."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def file_checksums(folder) -> dict[str, str]:
    """sha256 of every file under ``folder`` but the marker, by path relative to it."""
    folder = Path(folder)
    return {
        p.relative_to(folder).as_posix(): file_sha256(p)
        for p in sorted(folder.rglob("*"))
        if p.is_file() and p.name != MARKER
    }


def entries(folder) -> list[str]:
    """Every file and folder under ``folder`` (links not followed) but the marker, by relative path."""
    folder = Path(folder)
    found = [
        (Path(root) / name).relative_to(folder).as_posix()
        for root, folders, files in os.walk(folder)
        for name in folders + files
    ]
    return sorted(set(found) - {MARKER})


def read_marker(folder, name: str = MARKER) -> dict | None:
    """The marker (or JSON object ``name``) of ``folder``, or None if it is missing, unreadable or no
    file (a pipe would block)."""
    path = Path(folder) / name
    try:
        data = json.loads(path.read_text(encoding="utf-8")) if path.is_file() else None
    except (OSError, ValueError, RecursionError):
        return None
    return data if isinstance(data, dict) else None


def foreign_content(folder: Path, written_by: str) -> tuple[str | None, bool]:
    """``(None, True)`` if ``folder`` is empty or holds only what ``written_by`` wrote there; else
    why not, and whether all it holds is still as this program wrote it (another command's output,
    which ``force`` may replace)."""
    try:
        names = set(os.listdir(folder))
    except OSError as exc:
        return f"cannot be listed ({exc.strerror or exc})", False
    if MARKER not in names:  # empty, or not ours
        why = f"it was not written by this program (it holds {min(names)})" if names else None
        return why, not names
    marker = read_marker(folder) or {}
    contents, files = marker.get("contents"), marker.get("files", {})
    named = isinstance(contents, list) and all(isinstance(name, str) for name in contents)
    if not (named or isinstance(contents, str)) or not isinstance(files, dict):
        return f"its marker {MARKER} is damaged", False
    now = file_checksums(folder) if files else {}
    changed = sorted(k for k in files.keys() | now.keys() if files.get(k) != now.get(k))
    extra = [] if contents == ANY_CONTENTS else sorted(set(entries(folder)) - {MARKER, *contents})
    if changed:
        return f"{changed[0]} was added, changed or removed since it was written", False
    if extra:
        return f"it holds {extra[0]}, which this program did not write", False
    other = marker.get("written_by")  # another command's output, intact: --force may replace it
    why = f"it holds the output of `{other}`, which `{written_by}` does not replace"
    return (why if other != written_by else None), True


def linked_from(folder) -> tuple[list[Path], str | None]:
    """Where the symbolic links under ``folder`` lead, and those under the folders they lead to, and
    so on; and why not every link could be looked at (else None)."""
    found, unlisted = [], []
    to_walk, budget, start = [Path(folder)], MAX_WALKED, real_path(folder)
    while to_walk and budget > 0:  # a link to / is not walked through the whole file system
        walk = itertools.islice(os.walk(to_walk.pop(), onerror=unlisted.append), budget)
        below = [Path(root) / name for root, folders, files in walk for name in folders + files]
        budget -= len(below) + 1
        new = sorted({real_path(path) for path in below if path.is_symlink()} - set(found))
        found += new
        # folders to walk in turn, not one that holds the input (/, a parent: found, and guarded
        # whole); os.path.isdir: a target that cannot be looked at (in /proc, say) is not walked
        to_walk += [target for target in new if os.path.isdir(target) and not _contains(target, start)]
    unlisted = [e for e in unlisted if not isinstance(e, FileNotFoundError)]  # a missing folder links nowhere
    hidden = f"{unlisted[0].filename} cannot be listed" if unlisted else None  # it may hide links
    return found, hidden or (None if budget > 0 else f"it holds or links to over {MAX_WALKED:,} entries")


def _check_guarded(real: Path, label: str, inputs, keep, keep_inside: bool = False) -> str | None:
    """Refuse an output folder that is, holds or (for an input, what it links to, this package, and
    with ``keep_inside`` the folders of ``keep``) lies inside a folder never replaced; returns why
    not every link under the inputs could be followed, if so."""
    links = [linked_from(p) for p in inputs]
    guarded = [(real_path(p), "the input sequence", True) for p in inputs]  # (folder, what, inside too)
    guarded += [(t, "what the input sequence links to", True) for found, _ in links for t in found]
    guarded += [(PACKAGE, "this package", True), (REPOSITORY_DATA.resolve(), "the sample data folder", False)]
    for where, what in ((Path.cwd, "the current folder"), (Path.home, "your home folder")):
        with contextlib.suppress(OSError, RuntimeError):  # no current folder (deleted) or no home
            guarded.append((where().resolve(), what, False))
    guarded += [(real_path(p), what, keep_inside) for p, what in (keep or {}).items()]
    for folder, what, inside in guarded:
        if _contains(real, folder) or (inside and _contains(folder, real)):
            where = "is" if real == folder else "holds" if _contains(real, folder) else "lies inside"
            raise OutputError(f"{label}: {where} {what}; choose another output folder")
    return next((why for _, why in links if why), None)


def check_target(
    target, *, written_by: str, force=False, inputs=(), keep=None, keep_inside=False, option=None
) -> str | None:
    """Raise :class:`OutputError` unless folder ``target`` may be (re)written by ``written_by``.

    ``inputs`` are folders the command reads; ``keep`` maps further folders never replaced to
    what they are (with ``keep_inside``, nor written inside). Restores a folder whose replacement
    was killed half-way. Returns what ``force`` replaces (path and why), if anything.
    """
    label, path = _label(target, option), Path(target)
    if path.is_symlink() and not path.exists():
        raise OutputError(f"{label}: a symbolic link to {os.readlink(path)}, which does not exist")
    real = real_path(path)
    unchecked = _check_guarded(real, label, inputs, keep, keep_inside)
    restore(real.parent, real.name)
    if not real.exists():
        above = next(p for p in real.parents if p.exists())
        if not above.is_dir():
            raise OutputError(f"{label}: cannot write there ({above} is a file)")
        return None
    if not real.is_dir() or os.path.ismount(real):  # a finished output is renamed into its place
        what = {True: "is a mount point, which a folder cannot be renamed over (give one inside it)"}
        raise OutputError(
            f"{label}: {what.get(real.is_dir(), 'is a file, not a folder')}; choose another output folder"
        )
    if unchecked:  # an existing folder may be one the input reads through a link not looked at
        raise OutputError(
            f"{label}: the folder exists, and whether the input reads it cannot be checked (the input: "
            f"{unchecked}); choose a new output folder"
        )
    why, ours = foreign_content(real, written_by)
    in_data = _contains(REPOSITORY_DATA.resolve(), real)  # beside the samples: tracked fixtures
    if why is not None and in_data:
        raise OutputError(
            f"{label}: the folder lies inside the sample data folder (no --force there) and {why}; "
            "choose another output folder"
        )
    if why is not None and not (force and ours):  # --force never deletes what we did not write
        fix = FIX_BY_FORCE[ours] if option else "move it away"  # an unnamed folder: no --force
        raise OutputError(f"{label}: the folder exists and {why}; {fix}")
    return None if why is None else f"{real} ({why})"


def claim_folder(target, written_by: str, *, option: str | None = None) -> Path:
    """Create and mark ``target``, a folder that ``written_by`` updates over many runs (a build
    folder), under the rules of :func:`check_target`; returns its resolved path."""
    check_target(target, written_by=written_by, option=option)
    real = real_path(target)
    try:
        real.mkdir(parents=True, exist_ok=True)
        write_atomic(real / MARKER, json.dumps({"written_by": written_by, "contents": ANY_CONTENTS}) + "\n")
    except OSError as exc:
        raise OutputError(f"{_label(target, option)}: cannot write there ({exc.strerror or exc})") from None
    return real


@contextlib.contextmanager
def _locked(folder: Path, shared: bool, label: str):
    """Hold a lock on ``folder`` (if it opens); a lock another command holds is :class:`OutputError`."""
    try:
        fd = os.open(folder, os.O_RDONLY | os.O_DIRECTORY)
    except OSError:
        yield
        return
    try:
        fcntl.flock(fd, (fcntl.LOCK_SH if shared else fcntl.LOCK_EX) | fcntl.LOCK_NB)
    except BlockingIOError:
        os.close(fd)
        doing = "replacing" if shared else "reading"
        raise OutputError(
            f"{label}: a running command is {doing} this folder; try again when it has finished"
        ) from None
    except OSError:  # no locks on this file system
        pass
    try:
        yield
    finally:
        os.close(fd)


#: Folders this process holds under :func:`reading`.
_READ: set[Path] = set()


@contextlib.contextmanager
def reading(folder):
    """Shared locks on ``folder``, on what its links lead to and on every folder above them while a
    command reads it (none is replaced meanwhile); a folder an outer ``reading`` holds is skipped."""
    real = real_path(folder)
    if real in _READ:
        yield
        return
    read = [real, *linked_from(folder)[0]]
    with contextlib.ExitStack() as stack:
        for path in dict.fromkeys(p for r in read for p in (r, *r.parents)):  # each folder once
            stack.enter_context(_locked(path, shared=True, label=str(path)))
        _READ.add(real)
        try:
            yield
        finally:
            _READ.discard(real)


class OutputFolder(contextlib.AbstractContextManager):  # its __enter__ returns it
    """A folder written whole: checked on entry (``check`` as :func:`check_target` takes it),
    filled in :attr:`path` (a temporary sibling), put in place by :meth:`commit`; on any exception
    (or without a commit) nothing is left behind. The marker records every file's sha256, and the
    folder is replaced later only while every file is as written.

    ::

        with OutputFolder("runs/x", "vo_lib run", inputs=[sequence_path]) as out:
            (out.path / "poses.txt").write_text(...)
            out.commit(seed=0)
    """

    def __init__(self, target, written_by: str, **check):
        self.target, self.written_by, self.committed = Path(target), written_by, False
        self._check = dict(written_by=written_by, **check)
        check_target(self.target, **self._check)
        self.real, self.label = real_path(self.target), _label(target, check.get("option"))
        clear_abandoned(self.real.parent, self.real.name)  # only once the target is accepted
        with _locked(self.real, shared=False, label=self.label):  # fail now, not after the work
            pass
        self._created = [p for p in reversed(self.real.parents) if not p.exists()]
        self.path = temporary(self.real)
        try:
            for folder in [*self._created, self.path]:
                folder.mkdir()  # with the umask's permissions
        except OSError as exc:
            self.discard()
            raise OutputError(f"{self.label}: cannot write there ({exc.strerror or exc})") from None

    def commit(self, **details) -> Path:
        """Write the marker (last: the folder is whole), check again, put it in place; returns the target."""
        if INTERRUPTED:
            raise INTERRUPTED[0]
        marker = {"written_by": self.written_by, "contents": entries(self.path), **details}
        marker["files"] = file_checksums(self.path)
        (self.path / MARKER).write_text(json.dumps(marker, indent=2, sort_keys=True) + "\n", encoding="utf-8")
        replacing = check_target(self.target, **self._check)
        if real_path(self.target) != self.real:  # a link repointed meanwhile: what was checked is elsewhere
            raise OutputError(f"{self.label}: now leads to {real_path(self.target)}; nothing was written")
        with _locked(self.real, shared=False, label=self.label):
            replaced = swap_in(self.path, self.real)
        self.committed = True  # from here on, a signal leaves the new folder in place
        if replacing:
            notice(f"--force: replaced {replacing}")
        remove_replaced(replaced, self.real)
        return self.target

    def discard(self) -> None:
        """Delete the temporary folder and the parents this folder created (while empty)."""
        if self.committed:
            return
        shutil.rmtree(self.path, ignore_errors=True)
        for folder in reversed(self._created):
            with contextlib.suppress(OSError):
                folder.rmdir()
        self._created = []

    def __exit__(self, exc_type, exc, tb) -> bool:
        self.discard()
        return False
