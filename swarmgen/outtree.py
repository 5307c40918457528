"""Output directories: what swarmgen may replace, and how, without losing anything.

The rules (docs/security.md):
- swarmgen owns only the files its manifest (`.swarmgen.json`) lists, and only while their content
  still has the listed SHA-256. The manifest is validated (schema, format, paths, digests), never
  trusted by its name. A non-empty directory without a valid manifest is refused.
- Files the manifest does not list (notes, a venv, colcon's `build/` and `install/`, `__pycache__`)
  are kept. A listed file that was edited since, or a user file where swarmgen must write, makes
  the command refuse, naming the files.
- A directory written by another command (compile, graph, simulate) is refused.
- The new tree is staged in a sibling directory first (nothing is touched if staging fails), then
  committed: a rename for a new directory, an atomic exchange (Linux `renameat2`) when the old tree
  holds only swarmgen's files, otherwise an in-place update behind a journal (the manifest lists
  the old and the pending new digests while files move, so a kill at any step leaves every file
  accounted for). Debris of an interrupted run (`.<name>.swarmgen-new-*`) is cleared on the next run.
- `-o` naming a symlink to a directory writes into that directory and keeps the link; modes follow
  the umask for new directories and are kept for existing ones.
"""

from __future__ import annotations

import contextlib
import errno
import hashlib
import json
import os
import re
import stat
import sys
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import field
from pathlib import Path, PurePosixPath

from swarmgen import __version__
from swarmgen.errors import SwarmgenError
from swarmgen.records import dataclass

MANIFEST = ".swarmgen.json"
FORMAT = 1
COMMANDS = ("compile", "graph", "simulate", "optimize")
MANIFEST_LIMIT = 16 * 2**20
_JOURNAL = ".swarmgen-journal.json"  # inside the staging directory only
_DIGEST = re.compile(r"[0-9a-f]{64}")
_SHOWN = 5  # files named in a refusal


class OutputError(SwarmgenError):
    """The output directory cannot be written safely; the message says why and what to do."""


@dataclass(frozen=True)
class Manifest:
    """The `.swarmgen.json` of an output tree: the files swarmgen wrote there, by digest."""

    command: str  # the command that wrote the tree
    source: str
    files: Mapping[str, str]  # relative POSIX path -> SHA-256 of its bytes
    pending: Mapping[str, str] = field(default_factory=dict)  # an update under way: new digests

    def owns(self, relative: str, digest: str) -> bool:
        """Whether the file at `relative` with this digest is one swarmgen wrote (or is writing)."""
        return digest in (self.files.get(relative), self.pending.get(relative))

    @property
    def listed(self) -> set[str]:
        """Every path the manifest names, written or pending."""
        return set(self.files) | set(self.pending)


Tree = Mapping[PurePosixPath, str | bytes]


def _bytes(content: str | bytes) -> bytes:
    return content.encode("utf-8") if isinstance(content, str) else content


def manifest_text(command: str, source: str, files: Tree) -> str:
    """The manifest of `files` (which must not include it), as written by `command`."""
    assert command in COMMANDS, command
    digests = {
        str(path): hashlib.sha256(_bytes(content)).hexdigest()
        for path, content in sorted(files.items())
    }
    payload = {
        "generator": "swarmgen",
        "command": command,
        "format": FORMAT,
        "source": source,
        "version": __version__,
        "files": digests,
    }
    return json.dumps(payload, indent=2, sort_keys=True) + "\n"


def parse_manifest(data: bytes) -> Manifest:
    """A manifest read from disk; raises OutputError naming what is wrong with it."""
    try:
        payload = json.loads(data.decode("utf-8"))
    except (UnicodeDecodeError, ValueError, RecursionError):
        raise OutputError("it is not JSON") from None
    if not isinstance(payload, dict):
        raise OutputError("it is not a JSON object")
    command = _command_of(payload)
    files = _digests(payload.get("files"), "files")
    pending = _digests(payload.get("pending", {}), "pending")
    source = payload.get("source", "")
    return Manifest(command, source if isinstance(source, str) else "", files, pending)


def _command_of(payload: dict[str, object]) -> str:
    generator, command = payload.get("generator"), payload.get("command")
    if generator == "swarmgen simulate" and command is None:  # written before format 1
        return "simulate"
    if generator != "swarmgen":
        raise OutputError(f"its generator is {generator!r}, not 'swarmgen'")
    if command is None and "format" not in payload:
        return "compile"  # before format 1, compile and graph wrote the same manifest
    if payload.get("format") != FORMAT:
        raise OutputError(f"format {payload.get('format')!r} is not {FORMAT}")
    if command not in COMMANDS:
        raise OutputError(f"command {command!r} is not one of {', '.join(COMMANDS)}")
    return str(command)


def _digests(value: object, key: str) -> dict[str, str]:
    if not isinstance(value, dict):
        raise OutputError(f"`{key}` is not an object")
    digests: dict[str, str] = {}
    for path, digest in value.items():
        if not isinstance(digest, str) or not _DIGEST.fullmatch(digest):
            raise OutputError(f"`{key}` entry {path!r} has no SHA-256 digest")
        if not _safe_relative(path):
            raise OutputError(f"`{key}` entry {path!r} is not a relative path inside the tree")
        digests[path] = digest
    return digests


def _safe_relative(path: str) -> bool:
    parts = PurePosixPath(path).parts
    return (
        bool(parts)
        and not path.startswith("/")
        and "\\" not in path
        and "\0" not in path
        and not any(p.startswith(".") for p in parts)  # swarmgen writes no hidden files
        and str(PurePosixPath(*parts)) == path
        and path != MANIFEST
    )


# --- the existing tree


@dataclass
class Existing:
    """What an output directory holds, sorted by who owns it."""

    manifest: Manifest | None = None
    ours: set[str] = field(default_factory=set)  # listed, digest verified
    edited: set[str] = field(default_factory=set)  # listed, but changed or no longer a file
    user: set[str] = field(default_factory=set)  # not listed (files, symlinks): kept
    directories: set[str] = field(default_factory=set)
    user_directories: set[str] = field(default_factory=set)  # no listed file under them: kept

    @property
    def replaceable(self) -> bool:
        """Only swarmgen's own files: the tree may be exchanged as a whole."""
        return not (self.user or self.user_directories or self.edited)


def target_of(out_dir: Path) -> Path:
    """The directory to write: `..` and symlinks resolved (a symlink to a directory is followed
    and kept), refused when it cannot be a directory."""
    if out_dir.is_symlink() and not out_dir.exists():
        raise OutputError(f"{out_dir} is a dangling symlink; remove it or give another directory")
    try:
        target = out_dir.resolve()
    except (OSError, RuntimeError) as err:  # a symlink loop
        raise OutputError(f"cannot resolve {out_dir}: {err}") from None
    if target.parent == target:
        raise OutputError(f"{out_dir} is the file system root; give a directory of its own")
    if target.exists() and not target.is_dir():
        raise OutputError(f"{out_dir} exists and is not a directory")
    for ancestor in target.parents:
        if ancestor.exists():
            if not ancestor.is_dir():
                raise OutputError(f"cannot create {out_dir}: {ancestor} is not a directory")
            break
    return target


def inspect(target: Path, command: str) -> Existing:
    """Sort the entries of `target` by owner; refuse a directory swarmgen may not write into."""
    found = Existing()
    if not target.exists():
        return found
    entries, found.directories = _walk(target)
    manifest_path = target / MANIFEST
    if MANIFEST not in entries:
        if entries or found.directories:
            raise OutputError(
                f"{target} is not empty and was not written by swarmgen (no {MANIFEST}); "
                "choose an empty or new directory"
            )
        return found
    found.manifest = _read_manifest(manifest_path)
    if found.manifest.command != command:
        raise OutputError(
            f"{target} holds the output of `swarmgen {found.manifest.command}`; "
            f"`swarmgen {command}` writes into a directory of its own"
        )
    for relative in sorted(entries - {MANIFEST}):
        _classify(target / relative, relative, found)
    found.edited |= found.directories & found.manifest.listed  # a file of ours became a directory
    implied = {str(p) for f in found.manifest.listed for p in PurePosixPath(f).parents}
    found.user_directories = found.directories - implied  # the user's, even an empty one
    return found


def _walk(root: Path) -> tuple[set[str], set[str]]:
    """Every non-directory entry (symlinks included, never followed) and every directory."""
    entries: set[str] = set()
    directories: set[str] = set()
    for top, dirs, files in os.walk(root, followlinks=False, onerror=_raise):
        here = PurePosixPath(Path(top).relative_to(root).as_posix())
        for name in dirs:
            (entries if os.path.islink(os.path.join(top, name)) else directories).add(
                str(here / name)
            )
        entries.update(str(here / name) for name in files)
    return entries, directories


def _raise(error: OSError) -> None:
    raise error


def _read_manifest(path: Path) -> Manifest:
    info = path.lstat()
    if not stat.S_ISREG(info.st_mode):
        raise OutputError(f"{path} is not a regular file; refusing to trust it as a manifest")
    if info.st_size > MANIFEST_LIMIT:
        raise OutputError(f"{path} is larger than a manifest can be; refusing to trust it")
    try:
        return parse_manifest(path.read_bytes())
    except OutputError as err:
        raise OutputError(
            f"{path} is not a valid swarmgen manifest ({err}); refusing to touch "
            f"{path.parent}: move it away or give a new directory"
        ) from None


def _classify(path: Path, relative: str, found: Existing) -> None:
    assert found.manifest is not None
    if relative not in found.manifest.listed:
        found.user.add(relative)
    elif stat.S_ISREG(path.lstat().st_mode) and found.manifest.owns(relative, _digest(path)):
        found.ours.add(relative)
    else:
        found.edited.add(relative)


def _digest(path: Path) -> str:
    hasher = hashlib.sha256()
    with path.open("rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            hasher.update(block)
    return hasher.hexdigest()


def _named(paths: Iterable[str]) -> str:
    ordered = sorted(paths)
    shown = ", ".join(ordered[:_SHOWN])
    return shown + (f" and {len(ordered) - _SHOWN} more" if len(ordered) > _SHOWN else "")


def _refuse_conflicts(target: Path, existing: Existing, new: Iterable[str]) -> None:
    if existing.edited:
        raise OutputError(
            f"{target}: files swarmgen wrote were changed since: {_named(existing.edited)}; "
            "move them away (or delete them) to regenerate"
        )
    kept = existing.user
    if not (kept or existing.user_directories or existing.directories):
        return  # a new or empty directory: nothing in it can stand where a file goes
    blocked = set()
    for relative in new:
        parents = {str(p) for p in PurePosixPath(relative).parents if str(p) != "."}
        if relative in kept or parents & kept:
            blocked.add(relative)
        elif relative in existing.user_directories or (
            relative in existing.directories and any(u.startswith(relative + "/") for u in kept)
        ):
            blocked.add(relative)  # a directory of the user's where a file must go
    if blocked:
        raise OutputError(
            f"{target}: swarmgen must write where files it did not write are: {_named(blocked)}; "
            "move them away"
        )


def preflight(out_dir: Path, command: str) -> Path:
    """Everything `write` checks before it writes: run before long work (a simulation) so that
    a bad `-o` is refused at once."""
    with _reported(out_dir):
        target = target_of(out_dir)
        _clear_debris(target)
        inspect(target, command)
        target.parent.mkdir(parents=True, exist_ok=True)
        os.rmdir(_mkdtemp(prefix=_staging_prefix(target), dir=target.parent))  # writable?
        return target


def write(files: Tree, out_dir: Path) -> None:
    """Make `out_dir` hold `files` (which include their manifest), under the module's rules."""
    manifest = parse_manifest(_bytes(files[PurePosixPath(MANIFEST)]))
    with _reported(out_dir):
        target = target_of(out_dir)
        _clear_debris(target)
        existing = inspect(target, manifest.command)
        new = {str(p) for p in files if str(p) != MANIFEST}
        _refuse_conflicts(target, existing, new)
        target.parent.mkdir(parents=True, exist_ok=True)
        staging = _stage(files, target)
        _commit(staging, target, existing, manifest)


@contextlib.contextmanager
def _reported(out_dir: Path) -> Iterator[None]:
    """The file system's refusals (a read-only parent, a name too long, a full disk) are the
    user's to fix: one line naming the path, not a traceback."""
    try:
        yield
    except OSError as err:
        where = err.filename or out_dir
        raise OutputError(f"cannot write {where}: {err.strerror or err}") from None


# --- staging and committing


def _stage(files: Tree, target: Path) -> Path:
    """The new tree in a sibling directory, its manifest written first so that debris of a kill
    lists what it holds."""
    staging = Path(_mkdtemp(prefix=_staging_prefix(target), dir=target.parent))
    try:
        (staging / MANIFEST).write_bytes(_bytes(files[PurePosixPath(MANIFEST)]))
        made = {staging}  # the directories made so far: each is made once
        for relative, content in sorted(files.items()):
            if str(relative) == MANIFEST:
                continue
            if not _safe_relative(str(relative)):
                raise OutputError(f"refusing to write outside the output directory: {relative}")
            path = staging / relative
            if path.parent not in made:
                path.parent.mkdir(parents=True, exist_ok=True)
                made.add(path.parent)
            path.write_bytes(_bytes(content))
    except BaseException:
        _remove_listed(staging, None)
        raise
    return staging


def _staging_prefix(target: Path) -> str:
    return f".{target.name[:100]}.swarmgen-new-"  # the sibling's name must fit in 255 bytes


def _mkdtemp(prefix: str, dir: Path) -> str:
    """`tempfile.mkdtemp`, imported when a tree is written: the pipeline imports this module for
    `validate` too, and tempfile brings shutil, bz2 and lzma."""
    import tempfile

    return tempfile.mkdtemp(prefix=prefix, dir=dir)


def _commit(staging: Path, target: Path, existing: Existing, manifest: Manifest) -> None:
    if not target.exists():
        os.chmod(staging, 0o777 & ~_umask())  # mkdtemp's 0700 is not what mkdir would give
        os.rename(staging, target)
    elif existing.replaceable and _exchange(staging, target):
        _remove_listed(staging, existing.manifest)  # the old tree, now at the staging path
    else:
        _update_in_place(staging, target, existing, manifest)


def _umask() -> int:
    current = os.umask(0o022)
    os.umask(current)
    return current


def _exchange(staging: Path, target: Path) -> bool:
    """Swap the two directories atomically (Linux renameat2 RENAME_EXCHANGE); False where the
    system or file system cannot, and the caller updates in place instead."""
    if not sys.platform.startswith("linux"):
        return False
    os.chmod(staging, stat.S_IMODE(target.stat().st_mode))
    import ctypes  # only to replace a tree: `validate` imports this module too

    libc = ctypes.CDLL(None, use_errno=True)
    if not hasattr(libc, "renameat2"):
        return False
    at_fdcwd, rename_exchange = -100, 2
    result = libc.renameat2(
        at_fdcwd, os.fsencode(staging), at_fdcwd, os.fsencode(target), rename_exchange
    )
    if result == 0:
        return True
    code = ctypes.get_errno()
    if code in (errno.EINVAL, errno.ENOSYS, errno.EOPNOTSUPP):
        return False
    raise OSError(code, os.strerror(code), str(target))


def _update_in_place(staging: Path, target: Path, existing: Existing, manifest: Manifest) -> None:
    """Move the staged files over ours, behind a journal: while files move, the manifest in
    `target` lists the old and the pending digests, so that every file stays accounted for."""
    old = existing.manifest or Manifest(manifest.command, manifest.source, {})
    journal = staging / _JOURNAL
    payload = json.loads((staging / MANIFEST).read_text(encoding="utf-8"))
    payload["files"] = {p: old.files[p] for p in sorted(existing.ours) if p in old.files}
    payload["pending"] = dict(manifest.files)
    journal.write_text(json.dumps(payload, indent=2, sort_keys=True) + "\n", encoding="utf-8")
    os.replace(journal, target / MANIFEST)
    # obsolete files first: a file of ours may stand where a new directory goes, or the reverse
    for relative in sorted(existing.ours - set(manifest.files)):
        (target / relative).unlink(missing_ok=True)
    _prune_directories(target, existing.directories - existing.user_directories)
    for relative in sorted(manifest.files):
        destination = target / relative
        destination.parent.mkdir(parents=True, exist_ok=True)
        os.replace(staging / relative, destination)
    os.replace(staging / MANIFEST, target / MANIFEST)
    _remove_listed(staging, None)


def _prune_directories(root: Path, candidates: Iterable[str]) -> None:
    """Remove the directories among `candidates` that are now empty, deepest first (a directory
    still holding anything, a user's file included, stays)."""
    for relative in sorted(candidates, key=lambda p: -p.count("/")):
        with contextlib.suppress(OSError):  # not empty: it holds a user's files or new output
            (root / relative).rmdir()


def _remove_listed(root: Path, manifest: Manifest | None) -> None:
    """Remove a staging or retired tree: the files its manifest lists (`None`: read it from the
    tree), the manifest, then the directories left empty. Anything else stays where it is."""
    if not root.is_dir():
        return
    if manifest is None:
        try:
            manifest = parse_manifest((root / MANIFEST).read_bytes())
        except (OSError, OutputError):
            manifest = Manifest("compile", "", {})
    entries, directories = _walk(root)
    # the manifest goes last: a kill half-way leaves a tree that still says what it holds
    for relative in [*sorted(entries & (manifest.listed | {_JOURNAL})), MANIFEST]:
        (root / relative).unlink(missing_ok=True)
    _prune_directories(root, directories)
    with contextlib.suppress(OSError):  # something not ours is inside: kept
        root.rmdir()


def _clear_debris(target: Path) -> None:
    """Staging trees left by a run that was killed (their names are swarmgen's own)."""
    parent = target.parent
    if not parent.is_dir():
        return
    prefix = _staging_prefix(target)
    for entry in parent.iterdir():
        if entry.name.startswith(prefix) and entry.is_dir() and not entry.is_symlink():
            _remove_listed(entry, None)


def diff_pairs(files: Tree, out_dir: Path) -> list[tuple[str, bytes | None, bytes | None]]:
    """(path, on disk, generated) for every path that differs between `files` and what `out_dir`
    holds of swarmgen's (generated paths and paths its manifest lists; other files are ignored,
    as `write` would keep them). Symlinks are never followed."""
    target = out_dir.resolve() if out_dir.exists() else out_dir
    listed: set[str] = set()
    if (target / MANIFEST).is_file():
        try:
            listed = _read_manifest(target / MANIFEST).listed
        except OutputError:
            listed = set()
    differences = []
    for relative in sorted({str(p) for p in files} | listed):
        old = _read_plain(target / relative)
        new = files.get(PurePosixPath(relative))
        new_bytes = _bytes(new) if new is not None else None
        if old != new_bytes:
            differences.append((relative, old, new_bytes))
    return differences


def _read_plain(path: Path) -> bytes | None:
    try:
        if not stat.S_ISREG(path.lstat().st_mode):
            return b"(not a regular file)\n"
        return path.read_bytes()
    except FileNotFoundError:
        return None
    except OSError as err:
        return f"(unreadable: {err.strerror})\n".encode()
