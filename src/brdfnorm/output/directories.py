"""Writing a directory of files (a report) atomically: build it beside the target, then rename it into place.

POSIX has no atomic exchange of two non-empty directories, so the new directory is written completely into a
fresh temporary sibling; only then is the old one renamed aside (to a unique temporary name), the new one
renamed to the target name (both renames on one filesystem), and the old one deleted. A failure at any point
before the renames — an exception, SIGINT or SIGTERM — removes the temporary directory and leaves an existing
directory untouched; nothing is ever half-written under the target name.

Concurrent writers of the same target serialize on an exclusive ``flock`` of the parent directory (held only
for the check-and-swap, so the minutes of work run in parallel): the last one to finish wins, and no
temporary or ``.old`` directory is left behind.

The target is replaced only when it is absent, empty, or was written by us before (recognised by
:data:`MARKER`), so an output path pointing at a directory of other files is refused instead of deleting
them; so are an empty path, the filesystem root, and the current directory or any of its ancestors.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

from ..errors import OutputError
from .files import current_umask, signals_cleanup, write_file

#: File that marks a directory as a brdfnorm report (so it may be replaced by the next run).
MARKER = ".brdfnorm-report"


class Stage:
    """The temporary directory the files are written into."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def write(self, name: str, data: str | bytes) -> None:
        """Write one file of the directory (``name`` relative to it)."""
        write_file(self.path / name, data)


def check_target(target: str | os.PathLike[str], option: str = "-o") -> Path:
    """The absolute target directory, or an OutputError saying why it cannot be (re)written (``option``: the flag
    that named it)."""
    where = os.fspath(target)
    if not where.strip():
        raise OutputError("empty output directory; give a directory name", where=repr(where))
    path = Path(os.path.abspath(where))
    if not path.name:
        raise OutputError("give a directory name for the report, not the filesystem root", where=where)
    real, cwd = os.path.realpath(path), os.path.realpath(os.getcwd())
    if cwd == real or cwd.startswith(real.rstrip(os.sep) + os.sep):
        raise OutputError("is the current directory or one of its parents; give a new directory name",
                          where=where)
    if not path.parent.is_dir():
        raise OutputError(f"parent directory {str(path.parent)!r} does not exist", where=where)
    if path.exists() or path.is_symlink():
        if not path.is_dir() or path.is_symlink():
            raise OutputError("exists and is not a directory", where=where)
        if not (path / MARKER).is_file() and any(path.iterdir()):
            raise OutputError("directory is not empty and holds no brdfnorm report; refusing to replace it "
                              f"(choose another {option})", where=where)
    return path


@contextlib.contextmanager
def staged(target: str | os.PathLike[str], marker_text: str, option: str = "-o") -> Iterator[Stage]:
    """Yield a :class:`Stage` beside ``target``; on normal exit the staged directory becomes ``target``."""
    path = check_target(target, option)
    where = os.fspath(target)
    with signals_cleanup():
        try:
            temporary = Path(tempfile.mkdtemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent))
        except OSError as error:
            raise OutputError(f"cannot create a directory beside it: {error.strerror}", where=where) from None
        try:
            os.chmod(temporary, 0o777 & ~current_umask())  # mkdtemp makes it private; this is an ordinary one
            stage = Stage(temporary)
            yield stage
            stage.write(MARKER, marker_text)
            with _locked(path.parent, where):
                check_target(path)  # it may have changed while the files were computed
                _swap(temporary, path, where)
        finally:
            shutil.rmtree(temporary, ignore_errors=True)


@contextlib.contextmanager
def _locked(directory: Path, where: str) -> Iterator[None]:
    """An exclusive advisory lock on ``directory`` (released when the descriptor closes)."""
    try:
        fd = os.open(directory, os.O_RDONLY | os.O_DIRECTORY)
    except OSError as error:
        raise OutputError(f"cannot lock the parent directory: {error.strerror}", where=where) from None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)


def _swap(new: Path, path: Path, where: str) -> None:
    old = Path(tempfile.mkdtemp(prefix=f".{path.name}.", suffix=".old", dir=path.parent))
    try:
        if path.exists():
            os.replace(path, old)  # `old` is an empty directory, which rename may replace
        try:
            os.rename(new, path)
        except OSError:
            if not path.exists() and any(old.iterdir()):
                os.rename(old, path)
            raise
    except OSError as error:
        raise OutputError(f"cannot move the new directory into place: {error.strerror}", where=where) from None
    finally:
        shutil.rmtree(old, ignore_errors=True)
