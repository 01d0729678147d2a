"""Atomic file output: write to a temporary file beside the target, then rename.

An interrupted write never leaves a partial file, and an existing file is only replaced
once the new one is complete. Temporary files are named ``.<target>.<pid>.<random>.part``;
a writer killed outright (SIGKILL, power loss) leaves one behind, and the next write to the
same folder removes it once its process is gone (``clean_stale_parts``).
"""

from __future__ import annotations

import contextlib
import errno
import json
import math
import os
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from acid.errors import OutputError

PART_SUFFIX = ".part"

#: A temporary file without a readable process id (older naming) counts as stale after this, s.
LEGACY_PART_AGE_S = 3600.0


def _pid_alive(pid: int) -> bool:
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # somebody else's live process
        return True
    return True


def _part_owner(name: str) -> int | None:
    """Process id in ``.<target>.<pid>.<random>.part``, or None for another naming."""
    stem = name[:-len(PART_SUFFIX)]
    parts = stem.rsplit(".", 2)
    if len(parts) == 3 and parts[1].isdigit():
        return int(parts[1])
    return None


def clean_stale_parts(folder: str | os.PathLike) -> list[Path]:
    """Remove temporary ``.*.part`` files in ``folder`` whose writer is no longer running.

    Returns the removed paths. Files of live processes (another acid writing right now) are
    kept; files without a process id in their name are removed once older than
    ``LEGACY_PART_AGE_S``.
    """
    folder = Path(folder)
    removed = []
    try:
        candidates = [p for p in folder.iterdir()
                      if p.name.startswith(".") and p.name.endswith(PART_SUFFIX)]
    except OSError:
        return removed
    now = time.time()
    for p in candidates:
        pid = _part_owner(p.name)
        try:
            if pid is not None:
                stale = pid != os.getpid() and not _pid_alive(pid)
            else:
                stale = now - p.lstat().st_mtime > LEGACY_PART_AGE_S
            if stale and not p.is_dir():
                p.unlink()
                removed.append(p)
        except OSError:
            continue
    return removed


def _reason(exc: OSError) -> str:
    return exc.strerror or exc.__class__.__name__


def check_writable_file(path: str | os.PathLike) -> Path:
    """Refuse, with an ``OutputError``, a file output that cannot be written.

    The target must not be a folder; its nearest existing ancestor must be a folder that
    this process can write into (missing folders in between are created by the write).
    """
    path = Path(path)
    if str(path) in ("", "."):
        raise OutputError(f"{path}: an output file needs a name")
    if path.is_dir():
        raise OutputError(f"{path}: is a folder, expected a file name")
    _check_parent(path)
    return path


def _check_parent(path: Path) -> None:
    parent = path.parent
    while not parent.exists():
        if parent.is_symlink():
            raise OutputError(f"{path}: cannot create folder {parent} (dangling link)")
        parent = parent.parent
    if not parent.is_dir():
        raise OutputError(f"{path}: cannot create it, {parent} is a file, not a folder")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise OutputError(f"{path}: folder {parent} is not writable")


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path in the target's folder; rename it onto ``path`` on success.

    Failures to create, write or rename (a folder in the way, a file where a folder should
    be, no permission, a full disk) are ``OutputError``; the temporary file is removed on
    every failure and on interruption.
    """
    path = Path(path)
    check_writable_file(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"{path}: cannot create folder {path.parent} ({_reason(exc)})") from None
    clean_stale_parts(path.parent)
    prefix = f".{path.name}.{os.getpid()}."
    tmp_path = None
    try:
        try:
            fd, tmp = tempfile.mkstemp(prefix=prefix, suffix=PART_SUFFIX, dir=path.parent)
        except OSError as exc:
            raise OutputError(f"{path}: cannot write in {path.parent} ({_reason(exc)})") from None
        tmp_path = Path(tmp)
        _ACTIVE.add(tmp_path)
        os.close(fd)
        try:
            yield tmp_path
            _fsync(tmp_path)
            # mkstemp creates 0600 files; give the result the mode a plain open() would have
            mode = path.stat().st_mode & 0o777 if path.exists() else 0o666 & ~_umask()
            os.chmod(tmp_path, mode)
            os.replace(tmp_path, path)
        except OSError as exc:
            if exc.errno in (errno.EISDIR, errno.ENOTEMPTY, errno.EEXIST):
                raise OutputError(f"{path}: is a folder, expected a file name") from None
            raise OutputError(f"{path}: cannot write ({_reason(exc)})") from None
    except BaseException:
        _remove_own_parts(path.parent, prefix, tmp_path)
        raise
    finally:
        _ACTIVE.discard(tmp_path)


#: Temporary files this process is writing right now (so that cleaning up after one
#: interrupted write never removes another writer's).
_ACTIVE: set = set()


def _remove_own_parts(folder: Path, prefix: str, tmp_path: Path | None) -> None:
    """Remove this write's temporary file, also when the interrupt came between its creation
    and its name reaching us (inside ``mkstemp``): then it is the one ``prefix`` (our process
    id) file no other write of this process holds."""
    candidates = [tmp_path] if tmp_path is not None else []
    with contextlib.suppress(OSError):
        candidates += [p for p in folder.iterdir()
                       if p.name.startswith(prefix) and p.name.endswith(PART_SUFFIX)
                       and p not in _ACTIVE]
    for p in candidates:
        with contextlib.suppress(OSError):
            p.unlink()


def _fsync(path: Path) -> None:
    """Flush a finished temporary file to disk before it replaces the target."""
    with open(path, "rb") as fh:
        os.fsync(fh.fileno())


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _json_default(obj):
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, Path):
        return str(obj)
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")


def json_safe(obj):
    """Recursively make ``obj`` strict-JSON ready: numpy arrays and scalars to Python, tuples
    to lists, non-finite floats (NaN, inf) to ``None``."""
    if isinstance(obj, dict):
        return {str(k): json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_safe(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return json_safe(obj.tolist())
    if isinstance(obj, np.generic):
        obj = obj.item()
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def write_json(path: str | os.PathLike, obj) -> Path:
    """Write ``obj`` as indented JSON, atomically (numpy arrays and scalars allowed)."""
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(obj, indent=2, default=_json_default, allow_nan=False) + "\n")
    return Path(path)


def write_text(path: str | os.PathLike, text: str) -> Path:
    """Write text atomically."""
    with atomic_path(path) as tmp:
        tmp.write_text(text)
    return Path(path)


def save_figure(fig, path: str | os.PathLike, dpi: int = 120) -> Path:
    """Save a matplotlib figure as PNG atomically and close it."""
    import matplotlib.pyplot as plt

    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi, format="png", bbox_inches="tight")
    plt.close(fig)
    return Path(path)


def file_sha256(path: str | os.PathLike) -> str:
    """Hex SHA-256 of a file (used as an input fingerprint in provenance records)."""
    import hashlib

    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()
