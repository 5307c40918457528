"""What a command does with the terminal and with the paths it is given: its standard streams,
how paths are shown in messages, and checking and writing the user's output files.

Standard streams (`install`, called by the console entry point before any command runs):

- a reader that closes early (`swarmgen replay ... | head -1`) is not an error: the rest of the
  output is discarded and the command finishes as it would have, with its own exit code;
- stdout that cannot be written (closed with `>&-`, a full disk, `/dev/full`) raises
  `StreamError`, which the command line reports as one line (exit 2);
- closed descriptors 0-2 are reopened on /dev/null first, so that a file swarmgen opens can
  never become its stdout.

Standard library only.
"""

from __future__ import annotations

import contextlib
import errno
import io
import os
import sys
import unicodedata
from pathlib import Path

from swarmgen.errors import SwarmgenError

SHOWN_MAX = 160  # characters of a path in a message; longer ones are cut in the middle
NAME_MAX = 255  # bytes of one path component (Linux, macOS)
PATH_MAX = 4096  # bytes of a whole path (Linux)


class StreamError(SwarmgenError):
    """stdout cannot be written (closed, full); the message says why, in one line."""


class OutputPathError(SwarmgenError):
    """An output path the command cannot write; the message says why, in one line."""


# --- standard streams


class _Output(io.RawIOBase):
    """File descriptor 1 or 2 as a raw stream with the rules of the module docstring."""

    def __init__(self, fd: int, name: str, *, closed: bool) -> None:
        super().__init__()
        self.fd, self.label, self.missing, self.discard = fd, name, closed, False

    def writable(self) -> bool:
        return True

    def fileno(self) -> int:
        return self.fd

    def isatty(self) -> bool:
        return not self.missing and os.isatty(self.fd)

    def write(self, data: bytes | bytearray | memoryview) -> int:  # type: ignore[override]
        size = len(data)
        if self.discard:
            return size
        if self.missing:
            self.discard = True
            self._fail("it is closed")
            return size
        try:
            return os.write(self.fd, data)
        except BrokenPipeError:  # the reader is gone: nobody is left to tell
            self.discard = True
            return size
        except OSError as err:
            self.discard = True  # report once; the rest of the output is dropped
            self._fail(err.strerror or str(err))
        return size

    def _fail(self, why: str) -> None:
        if self.fd == 1:
            raise StreamError(f"cannot write to stdout: {why}")
        # stderr: there is nowhere to report it; the exit code still tells


def _reopen_missing() -> set[int]:
    """Put /dev/null on closed descriptors 0-2; returns the ones that were closed."""
    missing = set()
    for fd in (0, 1, 2):
        try:
            os.fstat(fd)
        except OSError:
            missing.add(fd)
            null = os.open(os.devnull, os.O_RDWR)
            if null != fd:
                os.dup2(null, fd)
                os.close(null)
    return missing


def install() -> None:
    """Replace sys.stdout and sys.stderr by streams with the module's rules."""
    missing = _reopen_missing()
    for fd, name in ((1, "stdout"), (2, "stderr")):
        old = getattr(sys, name)
        raw = _Output(fd, name, closed=fd in missing)
        stream = io.TextIOWrapper(
            io.BufferedWriter(raw),  # type: ignore[type-var]  # typeshed wants a FileIO-like raw
            encoding=getattr(old, "encoding", None) or "utf-8",
            # paths that are not UTF-8 are written back as the bytes they were given as
            errors="surrogateescape" if fd == 1 else "backslashreplace",
            line_buffering=fd == 2 or bool(old is not None and old.line_buffering),
            write_through=fd == 2,
        )
        setattr(sys, name, stream)


# --- paths in messages


def shown(path: object) -> str:
    """`path` for a one-line message: control characters and bytes that are not UTF-8 escaped
    (a name with a newline cannot forge a second line), a very long path cut in the middle."""
    text = os.fspath(path) if isinstance(path, os.PathLike) else str(path)
    out = []
    for char in text:
        if 0xDC80 <= ord(char) <= 0xDCFF:  # os.fsdecode's stand-in for an undecodable byte
            out.append(f"\\x{ord(char) - 0xDC00:02x}")
        elif unicodedata.category(char) in ("Cc", "Cf", "Zl", "Zp"):
            out.append(repr(char)[1:-1] if ord(char) < 0x7F else f"\\u{ord(char):04x}")
        else:
            out.append(char)
    result = "".join(out)
    if len(result) > SHOWN_MAX:
        half = (SHOWN_MAX - 3) // 2
        result = f"{result[:half]}...{result[-half:]}"
    return result


# --- output paths


def _length_problem(path: Path) -> str | None:
    whole = len(os.fsencode(path.absolute()))
    if whole >= PATH_MAX:
        return f"the path is too long ({whole:,} bytes; the limit is {PATH_MAX:,})"
    for part in path.parts:
        size = len(os.fsencode(part))
        if size > NAME_MAX:
            return f"the name {shown(part)!r} is too long ({size} bytes; the limit is {NAME_MAX})"
    return None


def _existing_ancestor(path: Path) -> Path:
    for parent in path.absolute().parents:
        if os.path.lexists(parent):
            return parent
    return Path("/")


def _creatable(directory: Path, option: str) -> list[Path]:
    """Make `directory` and its missing parents now (a real test: permissions, read-only
    file systems and files in the way all answer); returns what was made, deepest last."""
    made: list[Path] = []
    missing = [directory, *directory.parents]
    for item in reversed(missing):
        if os.path.lexists(item):
            if not item.is_dir():
                remove_made(made)
                what = "a file" if item.is_file() else "something else"
                raise OutputPathError(
                    f"{option} {shown(directory)}: {shown(item)} is {what}, not a directory"
                )
            continue
        try:
            item.mkdir()
        except OSError as err:
            remove_made(made)
            raise OutputPathError(
                f"{option} {shown(directory)}: cannot create {shown(item)}: {err.strerror}"
            ) from None
        made.append(item)
    return made


def remove_made(made: list[Path]) -> None:
    """Remove the directories a check made (deepest first), if they are still empty."""
    for item in reversed(made):
        with contextlib.suppress(OSError):
            item.rmdir()


def check_new_directory(path: Path, option: str) -> None:
    """`path` must not exist and must be creatable (`--record DIR`); nothing is left behind."""
    problem = _length_problem(path)
    if problem:
        raise OutputPathError(f"{option}: {problem}")
    if os.path.lexists(path):
        kind = "a dangling symlink" if not path.exists() else "it exists"
        raise OutputPathError(f"{option} {shown(path)}: {kind}; {option} writes a new directory")
    remove_made(_creatable(path.absolute(), option))


def check_directory(path: Path, option: str) -> list[Path]:
    """`path` is a directory or can be made one (`schema -o DIR`): made now (returned, so a
    failure later can remove them again)."""
    problem = _length_problem(path)
    if problem:
        raise OutputPathError(f"{option}: {problem}")
    return _creatable(path.absolute(), option)


def check_file(path: Path, option: str) -> list[Path]:
    """`path` can be written as a file (`--csv FILE`): not a directory, its directory made
    (returned) and writable; an existing file is left as it is."""
    problem = _length_problem(path)
    if problem:
        raise OutputPathError(f"{option}: {problem}")
    if path.is_dir():
        raise OutputPathError(f"{option} {shown(path)}: is a directory; give a file name")
    import tempfile  # here, not at the top: every command's start-up imports this module

    made = _creatable(path.absolute().parent, option)
    try:
        with tempfile.NamedTemporaryFile(dir=path.absolute().parent, prefix=".swarmgen-"):
            pass
    except OSError as err:
        remove_made(made)
        raise OutputPathError(f"{option} {shown(path)}: cannot write: {err.strerror}") from None
    return made


def write_file(path: Path, data: bytes, option: str) -> None:
    """Write `data` to `path` atomically (a temporary file renamed over it): a reader never
    sees half a file, and a failure leaves the old one."""
    import tempfile  # as in check_file

    temporary: str | None = None
    try:
        descriptor, temporary = tempfile.mkstemp(dir=path.absolute().parent, prefix=".swarmgen-")
        with os.fdopen(descriptor, "wb") as handle:
            handle.write(data)
        os.chmod(temporary, 0o666 & ~_umask())
        os.replace(temporary, path)
    except OSError as err:
        if temporary is not None:
            with contextlib.suppress(OSError):
                os.unlink(temporary)
        reason = err.strerror or errno.errorcode.get(err.errno or 0, str(err))
        raise OutputPathError(f"{option} {shown(path)}: cannot write: {reason}") from None


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask
