"""Files and folders put in place whole, and what a killed process left finished or cleared.

A folder is written into a temporary sibling ``.NAME.vo_lib-PID-HOST-RANDOM.tmp`` and put in place
by :func:`swap_in`: on Linux swapped with the previous ``NAME`` in one step (``renameat2``,
``RENAME_EXCHANGE``), so ``NAME`` is always the previous folder or the new one, whole. Elsewhere the
previous folder is first renamed to ``.NAME.vo_lib-PID-HOST-RANDOM.old``; a kill between the two
renames is undone by :func:`restore` (run by the next command beside it). Other temporaries of dead
processes are deleted by the next command that goes on to write ``NAME`` (:func:`clear_abandoned`).
A file is replaced whole by :func:`write_atomic`.
"""

from __future__ import annotations

import contextlib
import ctypes
import errno
import hashlib
import os
import re
import secrets
import shutil
import signal
import socket
import sys
import threading
from pathlib import Path

#: A temporary's name: its random part is what ``tempfile`` or ``secrets.token_hex(4)`` gives, nothing else.
_TEMPORARY = re.compile(r"\.(.+)\.vo_lib-(\d+)-([0-9a-f]{8})-[a-z0-9_]{8}\.(tmp|old)")


def notice(message: str) -> None:
    """One line on stderr for something the user should know that is not an error."""
    print(f"notice: {message}", file=sys.stderr)


#: This machine, in the names of temporaries: only its own processes' temporaries are judged.
HOST = hashlib.sha1(socket.gethostname().encode()).hexdigest()[:8]


def real_path(path) -> Path:
    """``path`` with its links resolved (a loop of links ends where it loops, without an error)."""
    return Path(os.path.realpath(path))


def inode(path) -> tuple[int, int] | None:
    """``(device, inode)`` of ``path`` (one folder under two names has one), or None if absent."""
    with contextlib.suppress(OSError):
        st = os.stat(path)
        return st.st_dev, st.st_ino
    return None


def _stem(name: str) -> str:
    """``name`` as a temporary's name holds it: whole, or where that would pass a file system's 255
    bytes, its first 30 characters and a hash of the whole."""
    if len(os.fsencode(name)) <= 150:
        return name
    return f"{name[:30]}~{hashlib.sha1(os.fsencode(name)).hexdigest()[:8]}"


def temporary(name_beside: Path) -> Path:
    """A new temporary's name beside ``name_beside``."""
    return name_beside.with_name(
        f".{_stem(name_beside.name)}.vo_lib-{os.getpid()}-{HOST}-{secrets.token_hex(4)}.tmp"
    )


def write_atomic(path, text: str) -> Path:
    """Replace the file ``path`` by ``text`` through a temporary file beside it."""
    path = Path(path)
    tmp = temporary(path)
    try:
        with open(tmp, "x", encoding="utf-8", errors="surrogateescape", newline="") as fh:  # the umask's mode
            fh.write(text)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    return path


def _gone(pid: int) -> bool:
    """Does process ``pid`` of this machine no longer run?"""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    except (OSError, OverflowError):  # it runs, as another user; or no process has that number
        pass
    return False


def _abandoned_beside(parent: Path, name: str) -> list[tuple[os.DirEntry, str]]:
    """(entry, kind) of every temporary (never a link) of ``name`` left by dead processes of this machine."""
    with contextlib.suppress(OSError):
        found = ((entry, _TEMPORARY.fullmatch(entry.name)) for entry in os.scandir(parent))
        return [
            (entry, m[4])
            for entry, m in found
            if m and (m[1], m[3]) == (_stem(name), HOST) and not entry.is_symlink() and _gone(int(m[2]))
        ]
    return []


def restore(parent: Path, name: str) -> None:
    """Rename back an ``.old`` folder of ``name`` whose replacement was killed between its two
    renames (``name`` missing, or an empty folder made since)."""
    original = Path(parent, name)
    for entry in (entry for entry, kind in _abandoned_beside(parent, name) if kind == "old"):
        with contextlib.suppress(OSError):  # only an empty folder goes (not a file, a link or a full one)
            os.rmdir(original)
        if not os.path.lexists(original):
            os.rename(entry.path, original)
            notice(f"restored {original}, whose replacement was interrupted")


def clear_abandoned(parent: Path, name: str) -> None:
    """Delete the temporaries of ``name`` left in ``parent`` by dead processes (after :func:`restore`)."""
    abandoned = [entry for entry, _ in _abandoned_beside(parent, name)]
    for entry in abandoned:  # what cannot go is left
        if entry.is_dir(follow_symlinks=False):
            shutil.rmtree(entry.path, ignore_errors=True)
        else:
            with contextlib.suppress(OSError):
                os.unlink(entry.path)
    stay = [entry.name for entry in abandoned if os.path.lexists(entry.path)]  # a read-only folder, say
    gone = [entry.name for entry in abandoned if entry.name not in stay]
    for names, said in ((gone, "removed"), (stay, "cannot remove")):
        if names:
            notice(f"{said} {len(names)} temporary folder(s) left by earlier runs: {', '.join(names)}")


def _exchange(a: Path, b: Path) -> bool:
    """Swap folders ``a`` and ``b`` in one step (Linux ``renameat2``); False where not possible."""
    try:
        renameat2 = ctypes.CDLL(None, use_errno=True).renameat2
    except (OSError, AttributeError, TypeError):
        return False
    at_fdcwd, rename_exchange = -100, 2
    if renameat2(at_fdcwd, os.fsencode(a), at_fdcwd, os.fsencode(b), rename_exchange) == 0:
        return True
    if ctypes.get_errno() in (errno.ENOSYS, errno.EINVAL, errno.EOPNOTSUPP):
        return False
    raise OSError(ctypes.get_errno(), os.strerror(ctypes.get_errno()), str(b))


def swap_in(complete: Path, target: Path) -> Path | None:
    """Put the whole folder ``complete`` (a ``.tmp`` sibling) at ``target``; returns the temporary
    that now holds what ``target`` held, if anything, for :func:`remove_replaced`."""
    try:
        os.rename(complete, target)  # no target, or an empty folder
        return None
    except OSError as exc:
        if exc.errno not in (errno.ENOTEMPTY, errno.EEXIST):
            raise
    if _exchange(complete, target):
        return complete
    aside, held = temporary(target).with_suffix(".old"), []
    try:  # Ctrl-C or SIGTERM waits for both renames; a kill between them is undone by restore()
        with signals_to(lambda signum, frame: held.append(signum)):
            os.rename(target, aside)
            os.rename(complete, target)
    finally:
        if held:
            signal.raise_signal(held[0])
    return aside


@contextlib.contextmanager
def signals_to(handler):
    """SIGINT and SIGTERM handled by ``handler`` meanwhile (in the main thread; elsewhere nothing changes)."""
    main_thread = threading.current_thread() is threading.main_thread()
    previous = {kind: signal.signal(kind, handler) for kind in (signal.SIGINT, signal.SIGTERM) if main_thread}
    defaults = {signal.SIGINT: signal.default_int_handler, signal.SIGTERM: signal.SIG_DFL}
    try:
        yield
    finally:
        for kind, old in previous.items():
            signal.signal(kind, defaults[kind] if old is None else old)


def remove_replaced(replaced: Path | None, target: Path) -> None:
    """Delete what :func:`swap_in` set aside; what cannot go keeps its temporary's name (for later)."""
    if replaced is None:
        return
    try:
        shutil.rmtree(replaced)
    except OSError as exc:  # the new folder is in place: what is left is only the old one
        notice(f"wrote {target}, but its previous contents stay in {replaced} ({exc.strerror or exc})")
