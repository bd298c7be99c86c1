"""Run a CasADi function as compiled C, with an on-disk cache and a plain fallback.

At sub-millisecond scale the cost of calling a CasADi function from Python (argument
conversion) outweighs the numerical work of a whole IK attempt. So the function is emitted as C
by CasADi's code generator, compiled once with the system C compiler into a shared library and
called through :mod:`ctypes` on preallocated NumPy buffers.

Libraries are cached under ``$BT_MANIP_IK_CACHE``, else ``$XDG_CACHE_HOME/bt-manip/ik``, else
``~/.cache/bt-manip/ik``, in a file named after a hash of the generated source and the compiler
command, so a changed model or solver gets a fresh build and concurrent processes never see a
half-written file (it is written under a temporary name, then renamed). Without a working
compiler (or with ``BT_MANIP_NO_COMPILE=1``) the same interface runs the function in CasADi's
own virtual machine: identical results, slower calls.

Usage::

    runner = load_runner(function)      # CompiledRunner or VirtualMachineRunner
    runner.inputs[0][:] = q0            # write inputs in place
    runner.run()
    q = runner.outputs[0]               # read outputs (overwritten by the next run)
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import shutil
import subprocess
import tempfile
from collections.abc import Hashable
from pathlib import Path

import casadi as ca
import numpy as np

from bt_manip.cache import cache_dir as shared_cache_dir

COMPILER_FLAGS = ("-O2", "-shared", "-fPIC")


def cache_dir() -> Path:
    """The folder that holds compiled libraries (``$BT_MANIP_IK_CACHE`` overrides it)."""
    return shared_cache_dir("ik", "BT_MANIP_IK_CACHE")


class VirtualMachineRunner:
    """Evaluates a CasADi function with CasADi itself (no compiler needed)."""

    compiled = False

    def __init__(self, function: ca.Function) -> None:
        self.function = function
        self.inputs = [np.zeros(function.nnz_in(i)) for i in range(function.n_in())]
        self.outputs = [np.zeros(function.nnz_out(i)) for i in range(function.n_out())]

    def run(self) -> None:
        """Evaluate the function on ``inputs`` and store the results in ``outputs``."""
        results = self.function.call([ca.DM(x) for x in self.inputs])
        for buf, value in zip(self.outputs, results, strict=True):
            buf[:] = np.asarray(value).ravel(order="F")


class CompiledRunner:
    """Calls the C version of a CasADi function through ctypes on fixed buffers."""

    compiled = True

    def __init__(self, function: ca.Function, library: ctypes.CDLL) -> None:
        self.function = function
        name = function.name()
        self._fn = getattr(library, name)
        self._fn.restype = ctypes.c_int
        cint = ctypes.c_longlong
        sizes = [cint() for _ in range(4)]
        getattr(library, name + "_work")(*[ctypes.byref(s) for s in sizes])
        n_arg, n_res, n_iw, n_w = (s.value for s in sizes)
        self.inputs = [np.zeros(function.nnz_in(i)) for i in range(function.n_in())]
        self.outputs = [np.zeros(function.nnz_out(i)) for i in range(function.n_out())]
        ptr = ctypes.POINTER(ctypes.c_double)
        arg = [x.ctypes.data_as(ptr) for x in self.inputs]
        res = [x.ctypes.data_as(ptr) for x in self.outputs]
        self._arg = (ptr * max(n_arg, 1))(*arg)
        self._res = (ptr * max(n_res, 1))(*res)
        self._iw = (cint * max(n_iw, 1))()
        self._w = (ctypes.c_double * max(n_w, 1))()
        checkout = getattr(library, name + "_checkout", None)
        self._mem = int(checkout()) if checkout is not None else 0
        self._call = self._fn
        self._args = (self._arg, self._res, self._iw, self._w, self._mem)

    def run(self) -> None:
        """Evaluate the function on ``inputs`` and store the results in ``outputs``."""
        if self._call(*self._args) != 0:
            raise RuntimeError(f"compiled function {self.function.name()} failed")


def _compiler() -> str | None:
    if os.environ.get("BT_MANIP_NO_COMPILE"):
        return None
    return shutil.which(os.environ.get("CC", "gcc")) or shutil.which("cc")


def _build(function: ca.Function, compiler: str) -> Path | None:
    """Generate and compile ``function``; the path of the cached library, or None."""
    generator = ca.CodeGenerator(f"{function.name()}_lib", {"with_header": False})
    generator.add(function)
    text = generator.dump().encode()
    key = hashlib.sha256(text + " ".join(COMPILER_FLAGS).encode()).hexdigest()[:20]
    folder = cache_dir()
    target = folder / f"{function.name()}-{key}.so"
    if target.is_file():
        return target
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory(prefix="bt-manip-cg-") as tmp:
            source = Path(tmp) / f"{function.name()}.c"
            source.write_bytes(text)
            scratch = Path(tmp) / target.name
            cmd = [compiler, *COMPILER_FLAGS, "-o", str(scratch), str(source), "-lm"]
            done = subprocess.run(cmd, capture_output=True, text=True, check=False)
            if done.returncode != 0 or not scratch.is_file():
                return None
            # Copy next to the target, then rename: readers never see a partial file.
            partial = folder / f".{target.name}.{os.getpid()}.tmp"
            shutil.copyfile(scratch, partial)
            os.replace(partial, target)
    except OSError:
        return None
    return target


FunctionRunner = CompiledRunner | VirtualMachineRunner
"""Either way of evaluating a CasADi function (compiled C or CasADi's virtual machine)."""


_LIBRARY_MEMO: dict[tuple[Hashable, str, str], Path] = {}
"""Libraries already found or built in this process, by (the caller's key of the function,
compiler, cache folder): generating the C source to find the cached file costs more than the
rest of loading it. An entry is used only while its file exists."""
_LIBRARY_MEMO_SIZE = 64


def load_runner(function: ca.Function, key: Hashable | None = None) -> FunctionRunner:
    """A runner for ``function``: compiled C when possible, CasADi's VM otherwise.

    ``key``, when given, must identify the function's graph completely (two functions with
    equal keys generate the same C source); the library found for it is then remembered for
    the process, so later calls skip the code generation."""
    compiler = _compiler()
    if compiler is None:
        return VirtualMachineRunner(function)
    memo = None if key is None else (key, compiler, str(cache_dir()))
    path = _LIBRARY_MEMO.get(memo) if memo is not None else None
    if path is None or not path.is_file():
        path = _build(function, compiler)
        if memo is not None and path is not None:
            if len(_LIBRARY_MEMO) >= _LIBRARY_MEMO_SIZE:
                _LIBRARY_MEMO.pop(next(iter(_LIBRARY_MEMO)), None)
            _LIBRARY_MEMO[memo] = path
    if path is None:
        return VirtualMachineRunner(function)
    try:
        # Loading the same file again reuses the already mapped library.
        library = ctypes.CDLL(str(path))
    except OSError:
        return VirtualMachineRunner(function)
    return CompiledRunner(function, library)
