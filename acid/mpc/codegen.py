"""CasADi functions as generated C: compiled once per structure, cached per user, loaded.

CasADi generates C for a whole NLP solver (fatrop, sqpmethod/qrqp, ...) as it does for any
function: the model, its derivatives *and* the solver's driver code. Compiled, the solver
skips CasADi's virtual machine and call overhead; the answers are bit-identical to the
solver run inside CasADi (the same algorithm on the same expressions).

:func:`compile_function` does it for any ``casadi.Function``:

1. **Generate** the C source (``casadi.CodeGenerator``).
2. **Key** it: SHA-256 of the source + CasADi version + compiler identity (its path and
   ``--version``) + flags. The source holds the problem's whole structure (horizon,
   sparsity, solver options), so a different problem gets a different key and the same
   problem the same key, in every process.
3. **Compile** it with the system C compiler (``$CC``, else ``cc``, ``gcc``, ``clang``) into
   the per-user cache (``$ACID_CACHE_DIR/nmpc``, else ``$XDG_CACHE_HOME/acid/nmpc`` or
   ``~/.cache/acid/nmpc``), atomically: the library is built under a temporary name and
   renamed into place, and a manifest beside it records its SHA-256. Concurrent first uses
   are serialised by a lock file (the second waits, then loads what the first built).
4. **Verify and load** it: the library's SHA-256 must match its manifest (a truncated or
   otherwise corrupted entry is rebuilt, never loaded), then ``ctypes`` loads it and
   :class:`CompiledFunction` calls it on preallocated numpy buffers (a few microseconds of
   overhead instead of CasADi's tens).

Solvers whose generated code calls a solver library (fatrop, hpipm) are linked against the
libraries shipped in the casadi wheel (``-L``/``-rpath`` to its folder, headers from its
``include``), so the compiled solver needs the casadi installation it was generated from
at run time (the cache key includes the CasADi version). For C that needs nothing but a C
compiler and libm, generate a self-contained plugin (``sqpmethod`` with ``qrqp``): see
:mod:`acid.mpc.export`.

Anything that goes wrong (no compiler, a compiler error, an unloadable library) raises
:class:`CodegenError` with a one-line reason; callers fall back to the CasADi function
(see :class:`acid.mpc.solver.NLPSolver`, which emits one :class:`CodegenWarning` notice).
"""

from __future__ import annotations

import contextlib
import ctypes
import functools
import hashlib
import json
import os
import re
import shlex
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import casadi as ca
import numpy as np

from acid._io import atomic_path
from acid.errors import AcidError

#: compiler flags of every build (optimised, position independent, room for 64 concurrent
#: memory slots of a stateful generated function such as an NLP solver)
CFLAGS = ("-O2", "-fPIC", "-shared", "-DCASADI_MAX_NUM_THREADS=64")
#: solver libraries that generated code may include, and what to link for them
RUNTIME_LIBRARIES = {"fatrop/": ("fatrop", "blasfeo"), "hpipm_": ("hpipm", "blasfeo"),
                     "blasfeo": ("blasfeo",)}
#: seconds a compilation may take before it counts as failed
COMPILE_TIMEOUT_S = 300.0


class CodegenError(AcidError):
    """Generated C could not be produced, compiled or loaded (one-line reason)."""


# ----------------------------------------------------------------------------- cache
def cache_dir() -> Path:
    """Folder of the compiled functions: ``$ACID_CACHE_DIR/nmpc``, else
    ``$XDG_CACHE_HOME/acid/nmpc`` or ``~/.cache/acid/nmpc``."""
    env = os.environ.get("ACID_CACHE_DIR")
    if env:
        return Path(env) / "nmpc"
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "acid" / "nmpc"


def casadi_dir() -> Path:
    """Folder of the installed casadi package (its shared libraries and ``include``)."""
    return Path(ca.__file__).resolve().parent


# -------------------------------------------------------------------------- compiler
def find_compiler() -> list[str] | None:
    """The C compiler command: ``$CC`` (may carry arguments), else ``cc``, ``gcc``,
    ``clang`` on the PATH; None when there is none."""
    env = os.environ.get("CC", "").strip()
    if env:
        return shlex.split(env)
    for name in ("cc", "gcc", "clang"):
        path = shutil.which(name)
        if path:
            return [path]
    return None


@functools.lru_cache(maxsize=8)
def _compiler_identity(cc: tuple[str, ...]) -> str:
    """``<resolved path>: <first line of --version>``; CodegenError if it does not run."""
    exe = shutil.which(cc[0]) or cc[0]
    try:
        out = subprocess.run([*cc, "--version"], capture_output=True, text=True, timeout=30)
    except (OSError, subprocess.SubprocessError) as exc:
        raise CodegenError(f"C compiler {' '.join(cc)!r} does not run ({exc})") from None
    if out.returncode != 0:
        raise CodegenError(f"C compiler {' '.join(cc)!r} does not run "
                           f"(--version exited {out.returncode})")
    first = (out.stdout or out.stderr).strip().splitlines()
    return f"{exe}: {first[0] if first else 'unknown version'}"


def link_flags(source: str) -> list[str]:
    """Include and link flags for the solver libraries ``source`` includes (see
    :data:`RUNTIME_LIBRARIES`), pointing at the casadi installation."""
    libs: list[str] = []
    for marker, names in RUNTIME_LIBRARIES.items():
        if re.search(r"#include\s*[<\"]" + re.escape(marker), source):
            libs += [n for n in names if n not in libs]
    if not libs:
        return []
    d = casadi_dir()
    return [f"-I{d / 'include'}", f"-L{d}", *(f"-l{n}" for n in libs), f"-Wl,-rpath,{d}"]


def generate_source(fn: ca.Function, name: str | None = None) -> str:
    """The C source of ``fn`` (and everything it calls), as one translation unit, with
    :func:`reset_function` appended when the function keeps memory."""
    cg = ca.CodeGenerator(name or fn.name(), {"with_header": False})
    try:
        cg.add(fn)
        source = cg.dump()
    except RuntimeError as exc:
        first = str(exc).strip().splitlines()[-1][:160] if str(exc).strip() else ""
        raise CodegenError(f"CasADi cannot generate C for {fn.name()!r} ({first})") from None
    return source + reset_function(source, fn.name())


def reset_function(source: str, name: str) -> str:
    """C of ``<name>_acid_reset(int mem)``: free and re-initialise one memory slot.

    A stateful generated function (an NLP solver keeps its solver object per slot) would
    otherwise hand a released slot, with what the last owner left in it, to the next
    instance: results would depend on what ran before in the process. With the reset
    every instance starts as a new CasADi function does. Empty when ``name`` keeps no
    memory (or the generated code does not have the expected shape).
    """
    m = re.search(r"CASADI_SYMBOL_EXPORT int " + re.escape(name)
                  + r"\(const casadi_real\*\* arg[^{]*\{\s*return (\w+)\(", source)
    if not m:
        return ""
    inner = m.group(1)
    if f"void {inner}_free_mem(int mem)" not in source or f"int {inner}_init_mem(int mem)" \
            not in source:
        return ""
    return (f"\nCASADI_SYMBOL_EXPORT int {name}_acid_reset(int mem) {{\n"
            f"  {inner}_free_mem(mem);\n  return {inner}_init_mem(mem);\n}}\n")


def build_key(source: str, cc: list[str], flags: list[str]) -> str:
    """Cache key: SHA-256 of source, CasADi version, compiler identity and flags."""
    h = hashlib.sha256()
    for part in (source, ca.__version__, _compiler_identity(tuple(cc)), " ".join(flags)):
        h.update(part.encode())
        h.update(b"\0")
    return h.hexdigest()[:24]


@contextlib.contextmanager
def _locked(path: Path):
    """Exclusive advisory lock on ``path`` (serialises concurrent builds of one entry)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        import fcntl
    except ImportError:  # pragma: no cover - no advisory locks: atomic renames still hold
        yield
        return
    with open(path, "a+") as fh:
        fcntl.flock(fh, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(fh, fcntl.LOCK_UN)


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _entry_ok(lib: Path, manifest: Path) -> str | None:
    """None when the cache entry is complete and intact, else what is wrong with it."""
    if not lib.is_file() and not manifest.is_file():
        return "missing"
    try:
        meta = json.loads(manifest.read_text())
        want = meta["sha256"]
    except (OSError, ValueError, KeyError, TypeError):
        return "its manifest is missing or unreadable"
    try:
        got = _sha256(lib)
    except OSError:
        return "its library is missing or unreadable"
    return None if got == want else "its library does not match its checksum"


def _compile(source: str, cc: list[str], flags: list[str], lib: Path) -> None:
    """Compile ``source`` into ``lib`` atomically (temporary name, then rename)."""
    with tempfile.TemporaryDirectory(prefix="acid-cg-") as tmp:
        src = Path(tmp) / f"{lib.stem}.c"
        src.write_text(source)
        with atomic_path(lib) as out:
            cmd = [*cc, *CFLAGS, str(src), "-o", str(out), *flags, "-lm"]
            try:
                res = subprocess.run(cmd, capture_output=True, text=True,
                                     timeout=COMPILE_TIMEOUT_S)
            except (OSError, subprocess.SubprocessError) as exc:
                raise CodegenError(f"C compiler {' '.join(cc)!r} failed to run ({exc})") from None
            if res.returncode != 0 or not out.is_file() or out.stat().st_size == 0:
                msg = (res.stderr or res.stdout).strip().splitlines()
                why = msg[0][:160] if msg else f"exit code {res.returncode}"
                raise CodegenError(f"C compiler {' '.join(cc)!r} failed on {lib.stem}.c ({why})")


def compiled_library(fn: ca.Function, name: str | None = None, cc: list[str] | None = None,
                     directory: Path | None = None) -> tuple[Path, dict]:
    """The compiled shared library of ``fn`` from the cache, building it when needed.

    Returns (library path, build info: key, compiler, seconds spent compiling or 0 when
    cached, whether a corrupted entry was replaced). Raises CodegenError.
    """
    cc = cc or find_compiler()
    if cc is None:
        raise CodegenError("no C compiler found (set CC, or install cc/gcc/clang)")
    name = name or fn.name()
    source = generate_source(fn, name)
    flags = link_flags(source)
    key = build_key(source, cc, flags)
    folder = Path(directory) if directory is not None else cache_dir()
    lib = folder / f"{name}-{key}.so"
    manifest = folder / f"{name}-{key}.json"
    info = {"key": key, "compiler": _compiler_identity(tuple(cc)), "compile_s": 0.0,
            "repaired": None, "path": str(lib)}
    with _locked(folder / f".{name}-{key}.lock"):
        problem = _entry_ok(lib, manifest)
        if problem is None:
            return lib, info
        if problem != "missing":
            info["repaired"] = f"cache entry {lib.name} was corrupted ({problem}); rebuilt"
            for f in (lib, manifest):
                with contextlib.suppress(FileNotFoundError):
                    f.unlink()
        t0 = time.perf_counter()
        _compile(source, cc, flags, lib)
        info["compile_s"] = time.perf_counter() - t0
        meta = {"name": name, "sha256": _sha256(lib), "casadi": ca.__version__,
                "compiler": info["compiler"], "flags": [*CFLAGS, *flags],
                "created": time.strftime("%Y-%m-%dT%H:%M:%S")}
        with atomic_path(manifest) as tmp:
            tmp.write_text(json.dumps(meta, indent=2) + "\n")
    return lib, info


# --------------------------------------------------------------------------- loading
_CINT = ctypes.c_longlong  # casadi_int of generated code (long long int)


class CompiledFunction:
    """A generated CasADi function loaded with ``ctypes``, called on numpy buffers.

    Parameters
    ----------
    fn : the CasADi function the library was generated from (gives the shapes).
    library : the compiled shared library.
    name : the exported symbol (default ``fn.name()``).

    Attributes
    ----------
    inputs, outputs : preallocated float64 buffers, one per input/output (``nnz`` entries,
        CasADi's column-major order). Fill ``inputs``, :meth:`call`, read ``outputs``.

    Notes
    -----
    Each instance checks out its own memory slot of the generated code (stateful functions
    such as solvers keep their workspace there) and works in its own buffers, so instances
    are independent; one instance must not be called from two threads at once.
    """

    def __init__(self, fn: ca.Function, library: Path, name: str | None = None):
        self.name = name or fn.name()
        self.library = Path(library)
        try:
            self._lib = ctypes.CDLL(str(self.library))
            self._fn = getattr(self._lib, self.name)
            sym = {s: getattr(self._lib, f"{self.name}_{s}")
                   for s in ("work", "incref", "decref", "checkout", "release", "n_in",
                             "n_out")}
        except (OSError, AttributeError) as exc:
            raise CodegenError(f"cannot load {self.library.name} ({exc})") from None
        for s in ("n_in", "n_out"):
            sym[s].restype = _CINT
        if (sym["n_in"]() != fn.n_in()) or (sym["n_out"]() != fn.n_out()):
            raise CodegenError(f"{self.library.name} does not match {fn.name()!r}")
        self._fn.restype = ctypes.c_int
        self._fn.argtypes = [ctypes.c_void_p] * 4 + [ctypes.c_int]
        sizes = [_CINT() for _ in range(4)]
        sym["work"](*(ctypes.byref(s) for s in sizes))
        n_arg, n_res, n_iw, n_w = (int(s.value) for s in sizes)
        self.inputs = [np.zeros(fn.nnz_in(i)) for i in range(fn.n_in())]
        self.outputs = [np.zeros(fn.nnz_out(i)) for i in range(fn.n_out())]
        self._arg = (ctypes.c_void_p * max(n_arg, 1))()
        self._res = (ctypes.c_void_p * max(n_res, 1))()
        for i, b in enumerate(self.inputs):
            self._arg[i] = b.ctypes.data
        for i, b in enumerate(self.outputs):
            self._res[i] = b.ctypes.data
        self._iw = np.zeros(max(n_iw, 1), dtype=np.int64)
        self._w = np.zeros(max(n_w, 1))
        self._iw_p, self._w_p = self._iw.ctypes.data, self._w.ctypes.data
        self._release, self._decref = sym["release"], sym["decref"]
        sym["incref"]()
        self._mem = int(sym["checkout"]())
        if self._mem < 0:
            self._decref()
            raise CodegenError(f"{self.library.name}: no free memory slot (too many "
                               "instances of one compiled function in this process)")
        reset = getattr(self._lib, f"{self.name}_acid_reset", None)
        if reset is not None:  # a reused slot starts afresh (see reset_function)
            reset.restype = ctypes.c_int
            reset(ctypes.c_int(self._mem))
        self._open = True

    def call(self) -> int:
        """Evaluate on :attr:`inputs` into :attr:`outputs`; returns the C return code
        (0: success; a solver generated with ``error_on_fail`` returns non-zero when it
        did not converge)."""
        return self._fn(self._arg, self._res, self._iw_p, self._w_p, self._mem)

    def __call__(self, *args) -> list[np.ndarray]:
        """Convenience: copy ``args`` into the inputs, call, return copies of the outputs
        (raises RuntimeError on a non-zero return code)."""
        for buf, a in zip(self.inputs, args, strict=False):
            buf[:] = a
        flag = self.call()
        if flag:
            raise RuntimeError(f"{self.name} returned {flag}")
        return [o.copy() for o in self.outputs]

    def close(self) -> None:
        """Give the memory slot back (idempotent; also on garbage collection)."""
        if getattr(self, "_open", False):
            self._open = False
            self._release(self._mem)
            self._decref()

    def abandon(self) -> None:
        """Forget the memory slot without releasing it (a call is still running in it,
        e.g. after a wall-clock timeout); the slot stays busy for the process's life."""
        self._open = False

    def __del__(self):
        with contextlib.suppress(Exception):
            self.close()


def compile_function(fn: ca.Function, name: str | None = None, cc: list[str] | None = None,
                     directory: Path | None = None) -> tuple[CompiledFunction, dict]:
    """``fn`` as generated, compiled (or cached) and loaded C; see the module docstring.

    Returns (CompiledFunction, build info). Raises :class:`CodegenError` with a one-line
    reason when anything fails; a corrupted cache entry is rebuilt once (reported in
    ``info["repaired"]``), and a library that verifies but does not load is rebuilt once.
    """
    lib, info = compiled_library(fn, name, cc, directory)
    try:
        return CompiledFunction(fn, lib, name), info
    except CodegenError as first:
        # intact checksum but unloadable (e.g. built against another libc): rebuild once
        for f in (lib, lib.with_suffix(".json")):
            with contextlib.suppress(FileNotFoundError):
                f.unlink()
        lib, info2 = compiled_library(fn, name, cc, directory)
        info2["repaired"] = f"cache entry {lib.name} did not load ({first}); rebuilt"
        return CompiledFunction(fn, lib, name), info2
