"""Reading a Modelio `.ramc` model component (a zip of `.exml` files) in memory, safely.

Everything is checked from the central directory BEFORE any member is decompressed: the member
count, each member's name (no absolute path, drive, `..`, backslash, NUL or control character,
no duplicate), its kind (no symbolic link, no encryption, stored or deflated only), each
member's declared size and compression ratio and the archive's total (zip bombs), and no
member is an archive itself. Then only the `.exml` members under `model/` are read, each with
its declared size enforced while decompressing (a header that lies is caught). Nothing is
written to disk. Every refusal is an SG067 diagnostic naming the archive and the member.
"""

from __future__ import annotations

import io
import stat
import struct
import zipfile
import zlib

from swarmgen import diagnostics as dg
from swarmgen.frontend.safexml import InputError, quoted
from swarmgen.records import dataclass
from swarmgen.span import Span

ZIP_MAGIC = b"PK\x03\x04"
MAX_MEMBERS = 10_000  # the 2019 CPSwarm library has 394 (mostly empty directories)
MAX_MEMBER_BYTES = 16 * 1024 * 1024
MAX_TOTAL_BYTES = 64 * 1024 * 1024  # the limit of one XML model file (safexml.MAX_BYTES)
MAX_RATIO = 100  # XML deflates 5 to 20 times; the library's largest member 14 times
RATIO_FLOOR = 64 * 1024  # below it a high ratio is harmless (an empty index page deflates 85x)
_METHODS = {zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED}
_ARCHIVE_SUFFIXES = (".ramc", ".zip", ".jar", ".jmdac", ".gz", ".tar", ".7z", ".rar", ".xz")
_EOCD = b"PK\x05\x06"
_EOCD_SIZE = 22


@dataclass(frozen=True)
class Member:
    """One `.exml` member read from the archive: its name and bytes."""

    name: str
    data: bytes


def read_archive(data: bytes, shown: str) -> list[Member]:
    """The `.exml` members of a `.ramc` (in archive order), or InputError (SG067)."""
    _check_count(data, shown)
    try:
        archive = zipfile.ZipFile(io.BytesIO(data))
    except (zipfile.BadZipFile, zipfile.LargeZipFile, OSError, ValueError, EOFError) as err:
        raise InputError(dg.MODELIO_ARCHIVE.at(Span(file=shown), error=_why(err))) from None
    with archive:
        infos = archive.infolist()
        _check_entries(infos, shown)
        wanted = [i for i in infos if _is_model_file(i.filename)]
        if not wanted:
            raise InputError(dg.MODELIO_ARCHIVE.at(Span(file=shown), "empty"))
        return [Member(i.filename, _read_member(archive, i, shown)) for i in wanted]


def member_file(shown: str, member: str) -> str:
    """How a member is named in spans: `archive.ramc!model/.../uid.exml`."""
    return f"{shown}!{member}"


def _why(err: BaseException) -> str:
    text = str(err) or type(err).__name__
    return text[:120]


def _check_count(data: bytes, shown: str) -> None:
    """The member count from the end-of-central-directory record, before `zipfile` builds an
    object per entry (a 64 MiB central directory could describe a million members)."""
    at = data.rfind(_EOCD, max(0, len(data) - _EOCD_SIZE - 0xFFFF))
    if at < 0 or at + _EOCD_SIZE > len(data):
        return  # zipfile reports the archive as not a zip (truncated)
    (count,) = struct.unpack_from("<H", data, at + 10)
    if count == 0xFFFF or count > MAX_MEMBERS:  # 0xFFFF: a zip64 count, above the limit anyway
        span = Span(file=shown)
        raise InputError(dg.MODELIO_ARCHIVE.at(span, "count", count=count, limit=MAX_MEMBERS))


def _check_entries(infos: list[zipfile.ZipInfo], shown: str) -> None:
    """Every check that needs no decompression, over every member (read or not)."""
    if len(infos) > MAX_MEMBERS:
        span = Span(file=shown)
        raise InputError(dg.MODELIO_ARCHIVE.at(span, "count", count=len(infos), limit=MAX_MEMBERS))
    total = sum(info.file_size for info in infos)  # before any member's own checks
    if total > MAX_TOTAL_BYTES:
        span = Span(file=shown)
        raise InputError(dg.MODELIO_ARCHIVE.at(span, "total", size=total, limit=MAX_TOTAL_BYTES))
    seen: set[str] = set()
    for info in infos:
        name = info.filename
        span = Span(file=member_file(shown, name))
        why = _unsafe_name(info.orig_filename, seen)
        if why is not None:
            raise InputError(dg.MODELIO_ARCHIVE.at(span, "name", member=_shown(name), why=why))
        seen.add(name)
        if stat.S_ISLNK(info.external_attr >> 16):
            raise InputError(dg.MODELIO_ARCHIVE.at(span, "link", member=_shown(name)))
        if name.lower().endswith(_ARCHIVE_SUFFIXES):
            raise InputError(dg.MODELIO_ARCHIVE.at(span, "nested", member=_shown(name)))
        _check_kind(info, span)
        _check_size(info, span)


def _unsafe_name(name: str, seen: set[str]) -> str | None:
    """Why a member name could escape or confuse a directory it were extracted into."""
    if not name:
        return "it is empty"
    if "\\" in name:
        return "it has a backslash"
    if any(ord(c) < 32 or c == "\x7f" for c in name):
        return "it has a control character"
    if name.startswith("/") or (len(name) > 1 and name[1] == ":"):
        return "it is an absolute path"
    if ".." in name.split("/"):
        return "it has a '..' component"
    if name in seen:
        return "it is in the archive twice"
    return None


def _check_kind(info: zipfile.ZipInfo, span: Span) -> None:
    if info.flag_bits & 0x1:
        raise InputError(
            dg.MODELIO_ARCHIVE.at(span, "method", member=_shown(info.filename), why="encrypted")
        )
    if info.compress_type not in _METHODS:
        why = f"compressed with method {info.compress_type}"
        raise InputError(
            dg.MODELIO_ARCHIVE.at(span, "method", member=_shown(info.filename), why=why)
        )


def _check_size(info: zipfile.ZipInfo, span: Span) -> None:
    member = _shown(info.filename)
    if info.file_size > MAX_MEMBER_BYTES:
        raise InputError(
            dg.MODELIO_ARCHIVE.at(
                span, "size", member=member, size=info.file_size, limit=MAX_MEMBER_BYTES
            )
        )
    ratio = info.file_size / max(info.compress_size, 1)
    if info.file_size > RATIO_FLOOR and ratio > MAX_RATIO:
        raise InputError(
            dg.MODELIO_ARCHIVE.at(
                span, "ratio", member=member, ratio=ratio, size=info.file_size, limit=MAX_RATIO
            )
        )


def _is_model_file(name: str) -> bool:
    return name.startswith("model/") and name.endswith(".exml")


def _read_member(archive: zipfile.ZipFile, info: zipfile.ZipInfo, shown: str) -> bytes:
    """The member's bytes; at most its declared size plus one is decompressed, so a header
    that understates the size is caught instead of trusted."""
    span = Span(file=member_file(shown, info.filename))
    try:
        with archive.open(info) as stream:
            data = stream.read(info.file_size + 1)
    except (zipfile.BadZipFile, OSError, EOFError, ValueError, zlib.error) as err:
        raise InputError(
            dg.MODELIO_ARCHIVE.at(span, "member", member=_shown(info.filename), error=_why(err))
        ) from None
    if len(data) > info.file_size:
        raise InputError(
            dg.MODELIO_ARCHIVE.at(
                span,
                "size",
                member=_shown(info.filename),
                size=len(data),
                limit=info.file_size,
            )
        )
    return data


def _shown(name: str) -> str:
    return quoted(name, 120)[1:-1]
