"""An output folder owned by one run: a lock, and the clean-up of what killed runs left.

``acid reproduce`` and ``acid sweep`` write many files into one folder over minutes. Two runs
into the same folder would overwrite each other's half-finished stages (two ``reproduce
--force`` used to die with ``OSError: Directory not empty``), and a run killed with SIGKILL
leaves hidden temporaries behind (``.name.PID.XXXX.part`` files of
:func:`acid._io.atomic_path`, stage folders under construction). :func:`claim` takes an
exclusive lock on the folder for the whole run and, once it holds the lock, removes those
temporaries: nothing else may be writing them.

The lock is ``fcntl.flock`` on ``FOLDER/.acid.lock``: the kernel releases it when the process
ends, however it ends (SIGKILL included), so a stale lock cannot block the next run. The file
records the holder (pid, command, start time) for the message a second run prints. Claims
are re-entrant within one process (the CLI claims the folder, the library claims it again).
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import time
from collections.abc import Iterator
from pathlib import Path

from acid.errors import AcidError

LOCK_NAME = ".acid.lock"
#: suffix of temporary folders that become a result by a rename (``tempfile.mkdtemp``)
TMP_DIR_SUFFIX = ".tmp"

_held: dict[Path, list] = {}  # folder -> [file object, depth]


class FolderBusyError(AcidError):
    """Another run holds the output folder."""


def _holder(lock_file: Path) -> str:
    from acid._readers import load_json

    try:
        d = load_json(lock_file, "lock file", max_bytes=64 * 1024)
    except AcidError:  # empty, tampered or gone
        return "another acid run"
    since = d.get("started")
    since = f", started {since}" if since else ""
    return f"{d.get('command') or 'another acid run'} (pid {d.get('pid', '?')}{since})"


def _lock(fh) -> bool:
    """Exclusive, non-blocking lock of an open file; False when someone else holds it."""
    try:
        import fcntl
    except ImportError:  # Windows
        import msvcrt

        try:
            msvcrt.locking(fh.fileno(), msvcrt.LK_NBLCK, 1)
        except OSError:
            return False
        return True
    try:
        fcntl.flock(fh.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        return False
    return True


def clean_stale(folder: str | os.PathLike) -> list[Path]:
    """Remove temporaries that a killed run left in ``folder``; returns what was removed.

    Hidden folders ending in ``.tmp`` (a stage or result under construction) anywhere below
    ``folder``, and the ``.part`` files of writers that are no longer running
    (:func:`acid._io.clean_stale_parts`, in every folder below). Call only while holding the
    folder (:func:`claim`): a live run's temporary folders look the same.
    """
    from acid._io import clean_stale_parts

    folder = Path(folder)
    removed: list[Path] = []
    if not folder.is_dir():
        return removed
    for dirpath, dirnames, _ in os.walk(folder):
        base = Path(dirpath)
        for d in list(dirnames):
            if d.startswith(".") and d.endswith(TMP_DIR_SUFFIX):
                shutil.rmtree(base / d, ignore_errors=True)
                removed.append(base / d)
                dirnames.remove(d)
        removed += clean_stale_parts(base)
    return removed


@contextlib.contextmanager
def claim(folder: str | os.PathLike, command: str) -> Iterator[Path]:
    """Hold ``folder`` for this run: create it, lock it, clean stale temporaries.

    Raises :class:`FolderBusyError` (one line, exit 2) when another process holds it.
    Re-entrant in one process. Yields the folder.
    """
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise AcidError(f"{folder}: output folder is a file")
    created = not folder.exists()   # made by this run: removed again if it stays empty
    made_parents = [a for a in folder.absolute().parents if not a.exists()]  # so are these
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise AcidError(f"{folder}: cannot create the output folder ({exc.strerror})") from None
    key = folder.resolve()
    if key in _held:
        _held[key][1] += 1
        try:
            yield folder
        finally:
            _held[key][1] -= 1
        return
    lock_file = folder / LOCK_NAME
    fh = open(lock_file, "a+")  # noqa: SIM115 (held open for the whole run)
    try:
        if not _lock(fh):
            raise FolderBusyError(f"{folder} is in use by {_holder(lock_file)}; wait for it to "
                                  "finish or choose another output folder")
        fh.seek(0)
        fh.truncate()
        fh.write(json.dumps({"pid": os.getpid(), "command": command,
                             "started": time.strftime("%Y-%m-%d %H:%M:%S")}))
        fh.flush()
        clean_stale(folder)
        _held[key] = [fh, 1]
        try:
            yield folder
        finally:
            del _held[key]
    finally:
        fh.close()  # releases the lock
        if created:
            _remove_if_only_the_lock(folder)
            for parent in made_parents:   # deepest first; one still holding anything stays
                with contextlib.suppress(OSError):
                    parent.rmdir()


def _remove_if_only_the_lock(folder: Path) -> None:
    """A folder this run created and that holds nothing but its lock (the run failed or was
    stopped before writing anything) goes again: nothing is left behind."""
    with contextlib.suppress(OSError):
        if [p.name for p in folder.iterdir()] == [LOCK_NAME]:
            (folder / LOCK_NAME).unlink()
            folder.rmdir()


__all__ = ["claim", "clean_stale", "FolderBusyError"]
