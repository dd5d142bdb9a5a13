"""Writing a report directory atomically: build it beside the target, then rename it into place.

A report is a directory (``index.html``, its images, ``data.json``), and POSIX has no atomic exchange of two
non-empty directories. So the new report is written completely into a fresh temporary sibling; only then is
the old one renamed aside, the new one renamed to the target name (both renames on one filesystem), and the
old one deleted. A failure at any point before the renames removes the temporary directory and leaves an
existing report untouched; a report is never half-written under the target name.

The target is replaced only when it is absent, empty, or a previous report (recognised by :data:`MARKER`), so
``-o`` pointing at a directory of other files is refused instead of deleting them.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

from ..errors import OutputError

#: File that marks a directory as a brdfnorm report (so it may be replaced by the next run).
MARKER = ".brdfnorm-report"


class Stage:
    """The temporary directory a report is written into."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def write(self, name: str, data: str | bytes) -> None:
        target = self.path / name
        try:
            if isinstance(data, bytes):
                target.write_bytes(data)
            else:
                target.write_text(data, encoding="utf-8")
        except OSError as error:
            raise OutputError(f"cannot write {name}: {error.strerror}", where=str(self.path)) from None


def check_target(target: str | Path) -> Path:
    """The absolute target directory, or an OutputError saying why it cannot be (re)written."""
    path = Path(os.path.abspath(target))
    where = str(target)
    if not path.name:
        raise OutputError("give a directory name for the report, not the filesystem root", where=where)
    if not path.parent.is_dir():
        raise OutputError(f"parent directory {str(path.parent)!r} does not exist", where=where)
    if path.exists() or path.is_symlink():
        if not path.is_dir() or path.is_symlink():
            raise OutputError("exists and is not a directory", where=where)
        if not (path / MARKER).is_file() and any(path.iterdir()):
            raise OutputError("directory is not empty and holds no brdfnorm report; refusing to replace it "
                              "(choose another -o)", where=where)
    return path


@contextlib.contextmanager
def staged(target: str | Path, marker_text: str) -> Iterator[Stage]:
    """Yield a :class:`Stage` beside ``target``; on normal exit the staged directory becomes ``target``."""
    path = check_target(target)
    try:
        temporary = Path(tempfile.mkdtemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent))
    except OSError as error:
        raise OutputError(f"cannot create a directory beside it: {error.strerror}", where=str(target)) from None
    try:
        os.chmod(temporary, 0o777 & ~_umask())  # mkdtemp makes it private; a report is an ordinary directory
        stage = Stage(temporary)
        yield stage
        stage.write(MARKER, marker_text)
        _swap(temporary, path, where=str(target))
    finally:
        shutil.rmtree(temporary, ignore_errors=True)


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _swap(new: Path, path: Path, where: str) -> None:
    check_target(path)  # it may have changed while the report was computed
    old = new.with_suffix(".old")
    try:
        if path.exists():
            os.rename(path, old)
        try:
            os.rename(new, path)
        except OSError:
            if old.exists():
                os.rename(old, path)
            raise
    except OSError as error:
        raise OutputError(f"cannot move the new report into place: {error.strerror}", where=where) from None
    shutil.rmtree(old, ignore_errors=True)
