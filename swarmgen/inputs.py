"""Reading the user's input files: regular files only, with the size limit enforced while reading.

A FIFO, a device (`/dev/zero`, `/dev/urandom`) or a `/proc` file reports a size of 0 (or none),
so checking `stat().st_size` first is not enough: they would be read forever or until memory runs
out. Every reader of a model, scenario or sweep file goes through `read_limited`.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from swarmgen.errors import SwarmgenError


class InputRefused(SwarmgenError):
    """The file cannot be read as an input; the message says why, in one line."""


def read_limited(path: Path, limit: int) -> bytes:
    """The bytes of the regular file `path`, refusing anything else and anything over `limit`
    bytes (counted while reading: a file that grows, or lies about its size, is still bounded)."""
    try:
        # O_NONBLOCK: opening a FIFO with no writer would otherwise block before we can refuse it
        descriptor = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    except FileNotFoundError:
        raise InputRefused("no such file") from None
    except IsADirectoryError:
        raise InputRefused("is a directory, not a file") from None
    except OSError as err:
        raise InputRefused(f"cannot read: {err.strerror or err}") from None
    mode = os.fstat(descriptor).st_mode
    if not stat.S_ISREG(mode) or str(path.resolve()).startswith("/proc/"):
        os.close(descriptor)
        if stat.S_ISDIR(mode):
            raise InputRefused("is a directory, not a file")
        raise InputRefused(f"is not a regular file ({_kind(mode)}); give a file on disk")
    with os.fdopen(descriptor, "rb") as handle:
        try:
            data = handle.read(limit + 1)
        except OSError as err:
            raise InputRefused(f"cannot read: {err.strerror or err}") from None
    if len(data) > limit:
        raise InputRefused(f"is larger than the limit of {_size(limit)}")
    return data


def _kind(mode: int) -> str:
    for test, name in (
        (stat.S_ISFIFO, "a FIFO"),
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISSOCK, "a socket"),
    ):
        if test(mode):
            return name
    return "a /proc file" if stat.S_ISREG(mode) else "not a regular file"


def _size(limit: int) -> str:
    return f"{limit // 2**20} MiB" if limit >= 2**20 else f"{limit} bytes"
