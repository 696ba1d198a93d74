"""Write a file so that it is either the old file or the complete new one, never a torn mix.

Every file Lantern writes (images, variance, checkpoints, screenshots, benchmark reports) goes
through `atomic_output`: the writer fills a temporary file in the same directory (a rename is only
atomic within one file system), which is flushed to disk and then renamed over the target. A
process killed at any moment leaves the previous file intact; at worst a hidden temporary file
(`.NAME.XXXXXXXX.tmp.EXT`) stays behind.
"""
from __future__ import annotations

import contextlib
import os
import secrets
from pathlib import Path
from typing import Iterator

TEMPORARY_MARKER = ".tmp"


def temporary_sibling(path: Path) -> Path:
    """A new, empty, uniquely named file beside `path`, keeping its extension (some writers choose
    the format by it). Created with the usual permissions (0666 less the umask), as a plain
    open() would, so the renamed file looks like any other the user writes."""
    while True:
        candidate = path.with_name(f".{path.name}.{secrets.token_hex(4)}{TEMPORARY_MARKER}{path.suffix}")
        try:
            os.close(os.open(candidate, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
            return candidate
        except FileExistsError:
            continue


def creation_problem(path: str | os.PathLike) -> str | None:
    """Why `atomic_output(path)` could not create its file, in words, or None when it can: the
    folders it would make and the temporary sibling it would write are made and removed again.
    Asking the file system itself is the only reliable check (permissions say nothing of /proc, a
    read-only mount or a full quota, and root passes every permission test)."""
    path = Path(path)
    made = []
    try:
        missing = [folder for folder in (path.parent, *path.parent.parents) if not folder.exists()]
        for folder in reversed(missing):
            try:
                folder.mkdir()
            except FileExistsError:
                continue
            except OSError as error:
                return f"cannot create the folder {folder} ({error.strerror or error})"
            made.append(folder)
        try:
            temporary_sibling(path).unlink()
        except OSError as error:
            return f"cannot create a file in {path.parent} ({error.strerror or error})"
        return None
    finally:
        for folder in reversed(made):
            with contextlib.suppress(OSError):
                folder.rmdir()


@contextlib.contextmanager
def atomic_output(path: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path to write `path`'s new content to; on a clean exit it replaces `path`.

    Parent directories are created. If the block raises (or is interrupted), the temporary file is
    removed and `path` is untouched.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = temporary_sibling(path)
    try:
        yield temporary
        _fsync_file(temporary)  # the data on disk before the name points at it
        os.replace(temporary, path)
    except BaseException:
        with contextlib.suppress(OSError):
            temporary.unlink()
        raise
    _fsync_directory(path.parent)  # the rename itself survives a power cut


def write_bytes_atomic(path: str | os.PathLike, data: bytes) -> None:
    with atomic_output(path) as temporary:
        temporary.write_bytes(data)


def write_text_atomic(path: str | os.PathLike, text: str, encoding: str = "utf-8") -> None:
    write_bytes_atomic(path, text.encode(encoding))


def _fsync_file(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _fsync_directory(directory: Path) -> None:
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:  # e.g. platforms where a directory cannot be opened
        return
    try:
        os.fsync(fd)
    except OSError:  # some file systems do not sync directories; the rename has happened anyway
        pass
    finally:
        os.close(fd)
