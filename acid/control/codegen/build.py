"""CasADi functions as generated C: compiled once per structure, cached per user, loaded.

CasADi generates C for a whole NLP solver (fatrop, sqpmethod/qrqp, ...) as it does for any
function: the model, its derivatives *and* the solver's driver code. Compiled, the solver
skips CasADi's virtual machine and call overhead; the answers are bit-identical to the
solver run inside CasADi (the same algorithm on the same expressions).

:func:`compile_function` does it for any ``casadi.Function``:

1. **Generate** the C source (``casadi.CodeGenerator``).
2. **Key** it: SHA-256 of the source + CasADi version + compiler identity (its
   ``--version`` line and target, never its path) + flags + the solver libraries it links.
   No install path enters the key (nor the library: it carries no ``rpath``), so one build
   serves every virtualenv and clone with the same source, CasADi version and compiler.
   The source holds the problem's whole structure (horizon, sparsity, solver options), so a
   different problem gets a different key and the same problem the same key.
3. **Compile** it with the system C compiler (``$CC``, else ``cc``, ``gcc``, ``clang``) into
   the per-user cache (``$ACID_CACHE_DIR/nmpc``, else ``$XDG_CACHE_HOME/acid/nmpc`` or
   ``~/.cache/acid/nmpc``), atomically: the library is built under a temporary name and
   renamed into place, and a manifest beside it records its SHA-256. The compiler runs in a
   session of its own, bounded by CPU time (:data:`COMPILE_CPU_S` per process, so a loaded
   machine slows it but does not kill it); on any exit, timeout or interrupt the whole
   process group (``cc1``, ``as``, ``ld``) is killed. Concurrent first uses are serialised
   by a lock file: the second process waits for the first one's build (at most
   :data:`LOCK_WAIT_S`, then it falls back) and loads it instead of compiling again.
4. **Verify and load** it: the library's SHA-256 must match its manifest and its ELF
   structure (headers, segments and sections) must lie within its size, at every load; once
   per build it is also loaded and called in a child process (recorded in the manifest). A
   corrupted entry is rebuilt, never loaded into this process (a truncated library would
   kill it with SIGBUS). Then ``ctypes`` loads it and :class:`CompiledFunction` calls it on
   preallocated numpy buffers (a few microseconds of overhead instead of CasADi's tens).

Solvers whose generated code calls a solver library (fatrop, hpipm) are linked against the
libraries shipped in the casadi wheel (headers from its ``include``); those libraries are
loaded from the running casadi installation before the compiled library, so the compiled
solver needs a casadi installation of the same version at run time (the cache key includes
the version). For C that needs nothing but a C compiler and libm, generate a self-contained
plugin (``sqpmethod`` with ``qrqp``): see :mod:`acid.control.codegen.export_paper`.

Anything that goes wrong (no compiler, a compiler error, an unloadable library, a cache
folder that cannot be used: read-only, a file in its place, a folder where the lock goes,
another process's build that does not finish) raises :class:`CodegenError` with a one-line
reason; callers fall back to the CasADi function (see
:class:`acid.control.codegen.solver.NLPSolver`,
which emits one :class:`CodegenWarning` notice).
"""

from __future__ import annotations

import contextlib
import ctypes
import errno
import functools
import hashlib
import json
import os
import re
import shlex
import shutil
import signal
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import casadi as ca
import numpy as np

from acid._io import atomic_path
from acid.errors import AcidError

#: optimisation level of sources of at least LARGE_SOURCE characters (None: OPT_FLAG for
#: all). Measured on the economic NMPC's solver (6.8 MB of C, ``benchmarks/bench_compile.py``,
#: both levels in one run on a loaded 2-core machine): -O1 compiles in 0.56x the CPU seconds
#: of -O2 (56 against 100) for steps 2.1 % slower and identical moves, so -O1 is better
#: end to end below about 10^5 steps per build. A function called on every control step
#: (``hot``, the economic NMPC's SQP: 1.4 MB of C, 10 CPU-s at -O2 against 5.6 at -O1, steps
#: 6 % faster) is built at OPT_FLAG whatever its size.
LARGE_OPT_FLAG: str | None = "-O1"
#: optimisation level of the other (small, seconds to compile) sources
OPT_FLAG = "-O2"
#: characters of C from which a source counts as large
LARGE_SOURCE = 1_000_000
#: the other compiler flags (position independent, room for 64 concurrent memory slots of a
#: stateful generated function such as an NLP solver; math functions that need not set
#: errno, so sqrt is the CPU's instruction: the same IEEE results, the economic NMPC's
#: generated SQP 3 % faster with bit-identical moves on the bench's UDDS replay)
BASE_CFLAGS = ("-fPIC", "-shared", "-fno-math-errno", "-DCASADI_MAX_NUM_THREADS=64")
#: flags for the host CPU's instruction set, used when the compiler resolves
#: ``-march=native`` (:func:`host_cpu`, which then enters the cache key: one build per
#: source + CasADi + compiler + flags + CPU); no fused multiply-adds, so the numbers are
#: those of a generic build. The economic NMPC's generated SQP about 3 % faster
#: (interleaved replay), bit-identical moves.
HOST_CFLAGS = ("-march=native", "-ffp-contract=off")
#: solver libraries that generated code may include, and what to link for them (in load
#: order: a library before the ones that need it)
RUNTIME_LIBRARIES = {"fatrop/": ("blasfeo", "fatrop"), "hpipm_": ("blasfeo", "hpipm"),
                     "blasfeo": ("blasfeo",)}
#: CPU seconds each compiler process may use (``RLIMIT_CPU``): generous (the economic
#: NMPC's solver takes about 50 at -O2) and independent of the machine's load
COMPILE_CPU_S = 900
#: wall-clock backstop for a compiler that stops using CPU (blocked), s
COMPILE_WALL_S = 7200.0
#: wall seconds a process waits for another one's build of the same entry before it falls
#: back (the build it waits on is itself bounded by COMPILE_CPU_S)
LOCK_WAIT_S = 1800.0
#: wall seconds the once-per-build child load of a library may take before it counts as
#: failed (a Python start-up and one call)
VERIFY_WALL_S = 300.0


def cflags(source: str = "", cc: list[str] | None = None, hot: bool = False
           ) -> tuple[str, ...]:
    """The compiler flags of a build of ``source`` (see :data:`LARGE_OPT_FLAG`; ``hot``: a
    function called on every control step, :data:`OPT_FLAG` whatever its size) by the
    compiler ``cc`` (:data:`HOST_CFLAGS` when it resolves them for this CPU)."""
    large = not hot and LARGE_OPT_FLAG is not None and len(source) >= LARGE_SOURCE
    host = HOST_CFLAGS if cc is not None and host_cpu(tuple(cc)) else ()
    return (LARGE_OPT_FLAG if large else OPT_FLAG, *host, *BASE_CFLAGS)


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


def _first_line(cc: tuple[str, ...], arg: str) -> str:
    try:
        out = subprocess.run([*cc, arg], capture_output=True, text=True, timeout=60)
    except (OSError, subprocess.SubprocessError) as exc:
        raise CodegenError(f"C compiler {' '.join(cc)!r} does not run ({exc})") from None
    if out.returncode != 0:
        raise CodegenError(f"C compiler {' '.join(cc)!r} does not run "
                           f"({arg} exited {out.returncode})")
    first = (out.stdout or out.stderr).strip().splitlines()
    return first[0] if first else "unknown"


@functools.lru_cache(maxsize=8)
def _compiler_identity(cc: tuple[str, ...]) -> str:
    """``<first line of --version> (<target>)``, free of install paths; CodegenError if the
    compiler does not run."""
    version = _first_line(cc, "--version")
    try:
        target = _first_line(cc, "-dumpmachine")
    except CodegenError:
        target = "unknown target"
    return f"{version} ({target})"


def runtime_libraries(source: str) -> list[str]:
    """The solver libraries ``source`` includes (see :data:`RUNTIME_LIBRARIES`), in load
    order."""
    libs: list[str] = []
    for marker, names in RUNTIME_LIBRARIES.items():
        if re.search(r"#include\s*[<\"]" + re.escape(marker), source):
            libs += [n for n in names if n not in libs]
    return libs


def link_flags(libs: list[str]) -> list[str]:
    """Include and link flags for the solver libraries ``libs``, pointing at the casadi
    installation (no ``rpath``: they are loaded by path before the library, see
    :func:`preload_libraries`)."""
    if not libs:
        return []
    d = casadi_dir()
    return [f"-I{d / 'include'}", f"-L{d}", *(f"-l{n}" for n in libs)]


def library_paths(libs: list[str]) -> list[Path]:
    """The casadi installation's files of the solver libraries ``libs``."""
    d = casadi_dir()
    return [d / f"lib{n}.so" for n in libs]


def preload_libraries(libs: list[str]) -> None:
    """Load the solver libraries ``libs`` of the running casadi installation (global
    symbols), so that a compiled library that needs them finds them by their soname."""
    for path in library_paths(libs):
        try:
            ctypes.CDLL(str(path), mode=ctypes.RTLD_GLOBAL)
        except OSError as exc:
            raise CodegenError(f"cannot load {path.name} of the casadi installation "
                               f"({exc})") from None


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


@functools.lru_cache(maxsize=8)
def host_cpu(cc: tuple[str, ...]) -> str:
    """The instruction set ``cc -march=native`` resolves to on this machine (its ``-march``
    and ``-m`` options, as the compiler passes them on), or "" when it does not."""
    try:
        out = subprocess.run([*cc, *HOST_CFLAGS, "-E", "-v", "-x", "c", os.devnull],
                             capture_output=True, text=True, timeout=60)
    except (OSError, subprocess.SubprocessError):
        return ""
    if out.returncode != 0:
        return ""
    for line in out.stderr.splitlines():
        opts = [w for w in line.split() if w.startswith(("-march=", "-m"))]
        if any(w.startswith("-march=") and w != "-march=native" for w in opts):
            return " ".join(opts)
    return ""


def build_key(source: str, cc: list[str], libs: list[str], hot: bool = False) -> str:
    """Cache key: SHA-256 of the source, the CasADi version, the compiler's identity, the
    flags, the host CPU they target (:func:`host_cpu`) and the linked solver libraries (by
    name: no install path enters it)."""
    h = hashlib.sha256()
    flags = cflags(source, cc, hot)
    cpu = host_cpu(tuple(cc)) if HOST_CFLAGS[0] in flags else ""
    for part in (source, ca.__version__, _compiler_identity(tuple(cc)), " ".join(flags), cpu,
                 " ".join(libs)):
        h.update(part.encode())
        h.update(b"\0")
    return h.hexdigest()[:24]


def _cache_fault(folder: Path, exc: BaseException) -> CodegenError:
    """A cache folder that cannot be used, as a one-line CodegenError."""
    if isinstance(exc, OSError):
        why = exc.strerror or type(exc).__name__
        where = exc.filename or folder
        return CodegenError(f"solver cache {where} cannot be used ({why})")
    return CodegenError(f"solver cache {folder} cannot be used ({exc})")


def _open_lock(path: Path) -> int:
    """File descriptor of the lock file ``path`` (created when missing)."""
    return os.open(path, os.O_RDWR | os.O_CREAT, 0o644)


@contextlib.contextmanager
def _locked(path: Path, wait_s: float):
    """Exclusive advisory lock on ``path`` (serialises concurrent builds of one entry).

    Yields True when held; False when the lock file cannot be created because the folder is
    read-only (an intact entry can still be loaded, nothing can be built). Waits at most
    ``wait_s`` for another holder, then raises CodegenError. A lock that is not a file
    raises OSError.
    """
    try:
        import fcntl
    except ImportError:  # pragma: no cover - no advisory locks: atomic renames still hold
        yield True
        return
    try:
        fd = _open_lock(path)
    except OSError as exc:
        if exc.errno in (errno.EACCES, errno.EROFS, errno.EPERM):
            yield False
            return
        raise
    try:
        deadline = time.monotonic() + wait_s
        delay = 0.05
        while True:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                break
            except BlockingIOError:
                if time.monotonic() >= deadline:
                    raise CodegenError(f"another process has been building {path.name[1:-5]}"
                                       f" for over {wait_s:g} s (lock {path}); not waiting "
                                       "longer") from None
                time.sleep(delay)
                delay = min(2 * delay, 1.0)
        try:
            yield True
        finally:
            fcntl.flock(fd, fcntl.LOCK_UN)
    finally:
        os.close(fd)


def _sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def elf_problem(data: bytes) -> str | None:
    """None when ``data`` is an ELF shared object whose headers, segments and sections all
    lie within its size, else what is wrong (a truncated library fails here)."""
    size = len(data)
    if size < 64 or data[:4] != b"\x7fELF":
        return "not an ELF file"
    cls, enc = data[4], data[5]
    if cls not in (1, 2) or enc not in (1, 2):
        return "unknown ELF class or byte order"
    e = "<" if enc == 1 else ">"
    if cls == 2:
        e_type, = struct.unpack_from(e + "H", data, 16)
        phoff, shoff = struct.unpack_from(e + "QQ", data, 32)
        phentsize, phnum, shentsize, shnum = struct.unpack_from(e + "HHHH", data, 54)
        ph_fmt, sh_fmt = e + "IIQQQQQQ", e + "IIQQQQIIQQ"
    else:
        e_type, = struct.unpack_from(e + "H", data, 16)
        phoff, shoff = struct.unpack_from(e + "II", data, 28)
        phentsize, phnum, shentsize, shnum = struct.unpack_from(e + "HHHH", data, 42)
        ph_fmt, sh_fmt = e + "IIIIIIII", e + "IIIIIIIIII"
    if e_type != 3:
        return "not a shared object"
    if phnum == 0 or phentsize < struct.calcsize(ph_fmt) or phoff + phnum * phentsize > size:
        return "program headers beyond the end of the file"
    if shnum and (shentsize < struct.calcsize(sh_fmt) or shoff + shnum * shentsize > size):
        return "section headers beyond the end of the file"
    for i in range(phnum):
        f = struct.unpack_from(ph_fmt, data, phoff + i * phentsize)
        offset, filesz = (f[2], f[5]) if cls == 2 else (f[1], f[4])
        if offset + filesz > size:
            return "a segment extends beyond the end of the file"
    for i in range(shnum):
        f = struct.unpack_from(sh_fmt, data, shoff + i * shentsize)
        sh_type, offset, sh_size = f[1], f[4], f[5]
        if sh_type != 8 and offset + sh_size > size:  # 8: SHT_NOBITS (.bss)
            return "a section extends beyond the end of the file"
    return None


def _read_manifest(manifest: Path) -> dict | None:
    try:
        meta = json.loads(manifest.read_text())
    except (OSError, ValueError, UnicodeDecodeError):
        return None
    if not isinstance(meta, dict) or not isinstance(meta.get("sha256"), str):
        return None
    return meta


def _entry_ok(lib: Path, manifest: Path) -> tuple[str | None, dict | None]:
    """(None, manifest) when the cache entry is complete and intact, else (what is wrong
    with it, None)."""
    if not lib.exists() and not manifest.exists():
        return "missing", None
    meta = _read_manifest(manifest)
    if meta is None:
        return "its manifest is missing or unreadable", None
    try:
        data = lib.read_bytes()
    except OSError:
        return "its library is missing or unreadable", None
    if _sha256(data) != meta["sha256"]:
        return "its library does not match its checksum", None
    bad = elf_problem(data)
    if bad:
        return f"its library is damaged: {bad}", None
    return None, meta


#: what the child process does with a library: load it (solver libraries first), call
#: ``<name>_n_in`` and print the result
_CHILD_LOAD = """\
import ctypes, sys
lib, name, pre = sys.argv[1], sys.argv[2], sys.argv[3:]
for p in pre:
    ctypes.CDLL(p, mode=ctypes.RTLD_GLOBAL)
f = getattr(ctypes.CDLL(lib), name + "_n_in")
f.restype = ctypes.c_longlong
print(f())
"""


def load_in_child(lib: Path, name: str, libs: list[str], n_in: int) -> str | None:
    """Load ``lib`` and call ``<name>_n_in`` in a child Python process: None when it
    answers ``n_in``, else what went wrong (a crash there cannot harm this process)."""
    cmd = [sys.executable, "-I", "-S", "-c", _CHILD_LOAD, str(lib), name,
           *(str(p) for p in library_paths(libs))]
    try:
        res = subprocess.run(cmd, capture_output=True, text=True, timeout=VERIFY_WALL_S,
                             stdin=subprocess.DEVNULL)
    except subprocess.TimeoutExpired:
        return f"loading it in a child process did not finish in {VERIFY_WALL_S:g} s"
    except OSError as exc:
        return f"cannot start a child process to load it ({exc.strerror})"
    if res.returncode < 0:
        try:
            sig = signal.Signals(-res.returncode).name
        except ValueError:
            sig = f"signal {-res.returncode}"
        return f"loading it killed a child process ({sig})"
    if res.returncode != 0:
        last = (res.stderr or "").strip().splitlines()
        return f"it does not load ({last[-1][:160] if last else res.returncode})"
    if res.stdout.strip() != str(n_in):
        return f"it does not match the function ({res.stdout.strip()[:40]!r} inputs)"
    return None


def _limit_cpu() -> None:  # pragma: no cover - runs in the child between fork and exec
    """``preexec_fn`` of the compiler: at most COMPILE_CPU_S CPU seconds per process."""
    import resource

    soft, hard = resource.getrlimit(resource.RLIMIT_CPU)
    want = COMPILE_CPU_S if hard == resource.RLIM_INFINITY else min(COMPILE_CPU_S, hard)
    with contextlib.suppress(ValueError, OSError):
        resource.setrlimit(resource.RLIMIT_CPU, (want, hard))


def _kill_group(proc: subprocess.Popen) -> None:
    """Kill the compiler's whole process group (``cc1``, ``as``, ``ld`` with it)."""
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(proc.pid, signal.SIGKILL)


def run_compiler(cmd: list[str], wall_s: float = COMPILE_WALL_S) -> tuple[int, str, float]:
    """Run a compiler command in a session of its own, bounded by COMPILE_CPU_S CPU
    seconds per process; its whole process group is killed when it exits, times out
    (``wall_s``, a backstop) or the caller is interrupted. Returns (exit code, its output,
    CPU seconds it used). Raises CodegenError when it cannot start or times out."""
    import resource

    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    # output to a file, not a pipe: a process the compiler leaves behind could hold a pipe
    # open (and the reader waiting) long after the compiler itself has exited
    with tempfile.TemporaryFile(mode="w+", errors="replace") as log:
        try:
            proc = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT,
                                    stdin=subprocess.DEVNULL, start_new_session=True,
                                    preexec_fn=_limit_cpu)
        except (OSError, subprocess.SubprocessError) as exc:
            raise CodegenError(f"C compiler {cmd[0]!r} failed to run ({exc})") from None
        try:
            proc.wait(timeout=wall_s)
        except subprocess.TimeoutExpired:
            raise CodegenError(f"C compiler {cmd[0]!r} did not finish in {wall_s:g} s; "
                               "stopped") from None
        finally:
            _kill_group(proc)  # whatever it left behind (also on a timeout or interrupt)
            if proc.returncode is None:
                proc.wait()
        log.seek(0)
        out = log.read()
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return proc.returncode, out, cpu


def _compile(source: str, cc: list[str], flags: list[str], lib: Path, hot: bool = False
             ) -> float:
    """Compile ``source`` into ``lib`` atomically (temporary name, then rename); returns
    the compiler's CPU seconds."""
    with tempfile.TemporaryDirectory(prefix="acid-cg-") as tmp:
        src = Path(tmp) / f"{lib.stem}.c"
        src.write_text(source)
        with atomic_path(lib) as out:
            cmd = [*cc, *cflags(source, cc, hot), str(src), "-o", str(out), *flags, "-lm"]
            code, text, cpu = run_compiler(cmd)
            if code != 0 or not out.is_file() or out.stat().st_size == 0:
                msg = text.strip().splitlines()
                if code in (-signal.SIGXCPU, -signal.SIGKILL) or "SIGXCPU" in text or \
                        "signal 24" in text:
                    why = f"stopped after {COMPILE_CPU_S} CPU seconds"
                else:
                    why = msg[0][:160] if msg else f"exit code {code}"
                raise CodegenError(f"C compiler {' '.join(cc)!r} failed on {lib.stem}.c ({why})")
    return cpu


def compiled_library(fn: ca.Function, name: str | None = None, cc: list[str] | None = None,
                     directory: Path | None = None, hot: bool = False) -> tuple[Path, dict]:
    """The compiled shared library of ``fn`` from the cache, building it when needed.

    Returns (library path, build info: key, compiler, wall and CPU seconds spent compiling
    or 0 when cached, whether a corrupted entry was replaced, the solver libraries to load
    first). Raises CodegenError, also for a cache folder that cannot be used.
    """
    cc = cc or find_compiler()
    if cc is None:
        raise CodegenError("no C compiler found (set CC, or install cc/gcc/clang)")
    name = name or fn.name()
    source = generate_source(fn, name)
    libs = runtime_libraries(source)
    key = build_key(source, cc, libs, hot)
    folder = Path(directory) if directory is not None else cache_dir()
    try:
        return _cached_build(fn, name, source, cc, libs, key, folder, hot)
    except CodegenError:
        raise
    except (OSError, AcidError) as exc:  # the folder, a file in its place, the lock ...
        raise _cache_fault(folder, exc) from None


def _cached_build(fn, name, source, cc, libs, key, folder: Path, hot: bool = False
                  ) -> tuple[Path, dict]:
    lib = folder / f"{name}-{key}.so"
    manifest = folder / f"{name}-{key}.json"
    info = {"key": key, "compiler": _compiler_identity(tuple(cc)), "compile_s": 0.0,
            "compile_cpu_s": 0.0, "repaired": None, "path": str(lib), "libraries": libs}
    folder.mkdir(parents=True, exist_ok=True)
    with _locked(folder / f".{name}-{key}.lock", LOCK_WAIT_S) as writable:
        problem, meta = _entry_ok(lib, manifest)
        if problem is None and meta.get("verified") != meta["sha256"]:
            problem = load_in_child(lib, name, libs, fn.n_in())
            if problem is None and writable:  # once per build
                meta["verified"] = meta["sha256"]
                with atomic_path(manifest) as tmp:
                    tmp.write_text(json.dumps(meta, indent=2) + "\n")
            elif problem is not None:
                problem = f"its library failed a trial load: {problem}"
        if problem is None:
            return lib, info
        if not writable:
            raise CodegenError(f"solver cache {folder} is read-only and holds no usable "
                               f"{lib.name} ({problem})")
        if problem != "missing":
            info["repaired"] = f"cache entry {lib.name} was corrupted ({problem}); rebuilt"
            for f in (lib, manifest):
                with contextlib.suppress(FileNotFoundError):
                    f.unlink()
        t0 = time.perf_counter()
        info["compile_cpu_s"] = _compile(source, cc, link_flags(libs), lib, hot)
        info["compile_s"] = time.perf_counter() - t0
        data = lib.read_bytes()
        bad = elf_problem(data) or load_in_child(lib, name, libs, fn.n_in())
        if bad:
            with contextlib.suppress(FileNotFoundError):
                lib.unlink()
            raise CodegenError(f"the freshly compiled {lib.name} is not usable ({bad})")
        meta = {"name": name, "sha256": _sha256(data), "verified": _sha256(data),
                "casadi": ca.__version__, "compiler": info["compiler"],
                "flags": [*cflags(source, cc, hot), *(f"-l{n}" for n in libs)],
                "created": time.strftime("%Y-%m-%dT%H:%M:%S"),
                "source_bytes": len(source), "compile_cpu_s": info["compile_cpu_s"],
                "compile_wall_s": info["compile_s"]}
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
                     directory: Path | None = None, hot: bool = False
                     ) -> tuple[CompiledFunction, dict]:
    """``fn`` as generated, compiled (or cached), verified and loaded C; see the module
    docstring. ``hot``: a function called on every control step (the economic NMPC's SQP),
    built at :data:`OPT_FLAG` whatever its size (:func:`cflags`).

    Returns (CompiledFunction, build info). Raises :class:`CodegenError` with a one-line
    reason when anything fails; a corrupted cache entry is rebuilt once (reported in
    ``info["repaired"]``), and a library that verifies but does not load is rebuilt once.
    """
    lib, info = compiled_library(fn, name, cc, directory, hot)
    preload_libraries(info["libraries"])
    try:
        return CompiledFunction(fn, lib, name), info
    except CodegenError as first:
        # verified but unloadable here (e.g. another process replaced it): rebuild once
        try:
            for f in (lib, lib.with_suffix(".json")):
                with contextlib.suppress(FileNotFoundError):
                    f.unlink()
        except OSError as exc:
            raise _cache_fault(lib.parent, exc) from None
        lib, info2 = compiled_library(fn, name, cc, directory, hot)
        info2["repaired"] = f"cache entry {lib.name} did not load ({first}); rebuilt"
        return CompiledFunction(fn, lib, name), info2
