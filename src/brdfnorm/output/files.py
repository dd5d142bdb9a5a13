"""The one writer for every file the product writes: :func:`write_file`.

``write_file(path, data)`` takes ``str`` (written as UTF-8) or ``bytes``:

* ``"-"`` writes to standard output.
* A regular file (or a new name) is written to a temporary sibling in the same directory and renamed over the
  target (POSIX ``rename`` is atomic within a filesystem): a reader sees the old content or the new, never a
  half-written file, and a failure leaves the old file as it was. The existing file's permission bits are kept;
  a new file gets ``0o666`` less the umask, as ``open()`` would give it (``mkstemp`` alone would make it 0600).
  A read-only file is refused, as ``open()`` would refuse it.
* A symlink is followed: the file it points to is replaced as above and the link stays a link. A dangling link
  is refused.
* A FIFO or a character device (``/dev/null``, a terminal) is written to directly — never replaced by a
  regular file; a FIFO with no reader is refused instead of blocking. Directories, sockets and block devices
  are refused.
* The temporary file is removed on any exception and on SIGTERM or SIGINT (:func:`signals_cleanup`).

Every refusal is an :class:`~brdfnorm.errors.OutputError` naming the path as given.
"""

from __future__ import annotations

import contextlib
import errno
import os
import signal
import stat
import sys
import tempfile
import threading
from collections.abc import Iterator
from pathlib import Path

from ..errors import OutputError

STDOUT = "-"


def write_file(path: str | os.PathLike[str], data: str | bytes) -> None:
    """Write ``data`` (text as UTF-8, or bytes) to ``path``; see the module docstring for each kind of target."""
    where = os.fspath(path)
    if not isinstance(data, (str, bytes)):
        raise TypeError(f"write_file takes str or bytes, not {type(data).__name__}")
    payload = data.encode("utf-8") if isinstance(data, str) else data
    if where == STDOUT:
        _write_stdout(payload)
        return
    if not where or not where.strip():
        raise OutputError("empty output path", where=repr(where))
    target = _resolve(where)
    try:
        mode = os.stat(target).st_mode
    except FileNotFoundError:
        _replace(target, payload, where, keep_mode=None)
        return
    except OSError as error:
        raise OutputError(f"cannot inspect the target: {error.strerror}", where=where) from None
    if stat.S_ISREG(mode):
        if not (mode & 0o222 and os.access(target, os.W_OK)):  # rename could replace it: its owner made it read-only
            raise OutputError("the file is read-only; refusing to replace it", where=where)
        _replace(target, payload, where, keep_mode=stat.S_IMODE(mode))
    elif stat.S_ISFIFO(mode) or stat.S_ISCHR(mode):
        _write_in_place(target, payload, where)
    elif stat.S_ISDIR(mode):
        raise OutputError("is a directory; give a file name", where=where)
    else:
        raise OutputError("is neither a regular file, a FIFO nor a character device; refusing to write it",
                          where=where)


def new_file_mode() -> int:
    """Permission bits a newly created file gets: 0o666 less the process umask."""
    return 0o666 & ~current_umask()


def current_umask() -> int:
    """The process umask (read by setting and restoring it, the only portable way)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _write_stdout(payload: bytes) -> None:
    stream = sys.stdout
    stream.flush()
    buffer = getattr(stream, "buffer", None)
    if buffer is not None:
        buffer.write(payload)
        buffer.flush()
    else:  # a text-only stream (e.g. captured in tests)
        stream.write(payload.decode("utf-8"))
        stream.flush()


def _resolve(where: str) -> Path:
    """The path to write: a symlink's final target (the link itself is kept), refused when it dangles."""
    path = Path(where)
    if path.is_symlink():
        resolved = Path(os.path.realpath(path))
        if not resolved.exists() and not resolved.parent.is_dir():
            raise OutputError(f"is a symlink to {str(resolved)!r}, which cannot be created", where=where)
        return resolved
    if path.name in ("", ".", ".."):
        raise OutputError("names a directory; give a file name", where=where)
    return path


def _replace(target: Path, payload: bytes, where: str, keep_mode: int | None) -> None:
    directory = target.parent
    if not directory.is_dir():
        raise OutputError(f"directory {str(directory)!r} does not exist", where=where)
    with signals_cleanup(), temporary_sibling(target, where) as (fd, temporary):
        try:
            with os.fdopen(fd, "wb") as handle:
                handle.write(payload)
                handle.flush()
                os.fchmod(handle.fileno(), new_file_mode() if keep_mode is None else keep_mode)
            os.replace(temporary, target)
        except OSError as error:
            raise OutputError(f"cannot write: {error.strerror}", where=where) from None


@contextlib.contextmanager
def temporary_sibling(target: Path, where: str) -> Iterator[tuple[int, str]]:
    """A temporary file ``.NAME.*.tmp`` beside ``target`` (fd, path), removed unless renamed away."""
    try:
        fd, temporary = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    except OSError as error:
        raise OutputError(f"cannot write here: {error.strerror}", where=where) from None
    try:
        yield fd, temporary
    finally:
        with contextlib.suppress(OSError):
            os.close(fd)
        with contextlib.suppress(FileNotFoundError):
            os.unlink(temporary)


def _write_in_place(target: Path, payload: bytes, where: str) -> None:
    """A FIFO or character device: opened for writing as it is (a FIFO without a reader is refused)."""
    try:
        fd = os.open(target, os.O_WRONLY | os.O_NONBLOCK | getattr(os, "O_NOCTTY", 0))
    except OSError as error:
        reason = "a FIFO with no reader" if error.errno == errno.ENXIO else error.strerror
        raise OutputError(f"cannot write: {reason}", where=where) from None
    try:
        os.set_blocking(fd, True)
        view = memoryview(payload)
        while view:
            view = view[os.write(fd, view):]
    except OSError as error:
        raise OutputError(f"cannot write: {error.strerror}", where=where) from None
    finally:
        os.close(fd)


class Terminated(SystemExit):
    """SIGTERM turned into an exception, so ``finally`` blocks remove temporary files (exit status 143)."""


@contextlib.contextmanager
def signals_cleanup() -> Iterator[None]:
    """Within the block, SIGTERM raises :class:`Terminated` (SIGINT already raises KeyboardInterrupt).

    Both unwind through ``finally`` clauses, which is how temporary files and directories are removed. Outside
    the main thread (where Python cannot install handlers) the block runs unchanged.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.getsignal(signal.SIGTERM)
    if previous not in (signal.SIG_DFL, None):  # someone else handles SIGTERM already (nested or an app)
        yield
        return

    def terminate(signum, frame):
        raise Terminated(128 + signum)

    signal.signal(signal.SIGTERM, terminate)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)
