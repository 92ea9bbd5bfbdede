"""Compile CasADi functions to C once and load them as the fast numeric path.

The C source that CasADi generates for a set of functions is compiled with the system C compiler
into a shared library kept in a cache directory (``$SWIM_CACHE_DIR``, else
``$XDG_CACHE_HOME/swim_model``, else ``~/.cache/swim_model``), named by the hash of the source, so
a model is compiled once per machine and rig. Without a C compiler the functions run in CasADi's
virtual machine: the same numbers, several times slower.

``native`` loads the same library through ctypes and calls each function's C entry point on preallocated numpy
buffers. CasADi's Python call (``f(*args)``, ``f.call``) converts every argument to a DM and every result back,
about 40-50 us a call on this 2-core host whatever the function does; the C entry point costs about 1 us plus the
arithmetic. Loops that call a small function every period (the simulator) use ``native``.
"""
from __future__ import annotations

import ctypes
import hashlib
import os
import shutil
import subprocess
import tempfile
import warnings
from pathlib import Path
from typing import Optional, Sequence

import casadi as ca
import numpy as np
import numpy.typing as npt

COMPILER_FLAGS = ("-O2", "-shared", "-fPIC")


def cache_dir() -> Path:
    """Where compiled models are kept.

    Returns
    -------
    pathlib.Path
        The cache folder.
    """
    if os.environ.get("SWIM_CACHE_DIR"):
        return Path(os.environ["SWIM_CACHE_DIR"])
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "swim_model"


def compile_library(functions: list[ca.Function], tag: str) -> Optional[Path]:
    """The shared library of the functions' generated C (compiled once, cached).

    Parameters
    ----------
    functions : list of casadi.Function
        The functions, generated into one C file.
    tag : str
        The cache name (codegen adds the source's hash).

    Returns
    -------
    pathlib.Path or None
        The library, or None without a C compiler.
    """
    compiler = shutil.which(os.environ.get("CC", "gcc"))
    if compiler is None:
        warnings.warn("no C compiler found: swim_model runs its models in CasADi's virtual machine (slower)")
        return None
    with tempfile.TemporaryDirectory() as work:
        generator = ca.CodeGenerator(f"{tag}.c", {"with_header": False})
        for function in functions:
            generator.add(function)
        source_path = Path(generator.generate(work + os.sep))
        source = source_path.read_bytes()
        digest = hashlib.sha256(source + " ".join(COMPILER_FLAGS).encode()).hexdigest()[:20]
        library = cache_dir() / f"{tag}_{digest}.so"
        if not library.exists():
            library.parent.mkdir(parents=True, exist_ok=True)
            partial = library.with_suffix(f".{os.getpid()}.tmp")
            subprocess.run([compiler, *COMPILER_FLAGS, str(source_path), "-o", str(partial), "-lm"],
                           check=True, capture_output=True)
            partial.replace(library)  # atomic: parallel processes never load a half-written library
    return library


def compiled(functions: list[ca.Function], tag: str) -> dict[str, ca.Function]:
    """The functions, compiled to C and loaded (or, without a compiler, as given), by name.

    Parameters
    ----------
    functions : list of casadi.Function
        The functions.
    tag : str
        The cache name.

    Returns
    -------
    dict of str to casadi.Function
        Each function by its name.
    """
    library = compile_library(functions, tag)
    if library is None:
        return {f.name(): f for f in functions}
    return {f.name(): ca.external(f.name(), str(library)) for f in functions}


def native(functions: list[ca.Function], tag: str,
           names: Optional[Sequence[str]] = None) -> dict[str, "NativeFunction"]:
    """The functions, compiled to C, as NativeFunction (the fast call path), by name.

    The library is the one ``compiled`` makes of the same list, so it is compiled once for both.

    Parameters
    ----------
    functions : list of casadi.Function
        The functions (dense arguments only for those loaded).
    tag : str
        The cache name.
    names : sequence of str, optional
        Load only these (default: all).

    Returns
    -------
    dict of str to NativeFunction
        Each loaded function by its name.
    """
    library = compile_library(functions, tag)
    loaded = None if library is None else ctypes.CDLL(str(library))
    return {f.name(): NativeFunction(f, loaded) for f in functions if names is None or f.name() in names}


class NativeFunction:
    """A function with dense inputs and outputs, called on buffers it owns.

    Write the inputs into ``inputs[i]`` (flat, column-major), call, read ``outputs[j]``. The buffers are reused:
    copy an output to keep it. With a library the C entry point is called through ctypes; without one (no compiler)
    the CasADi function itself, into the same buffers. One instance is one set of buffers: not for concurrent use
    from threads.

    Parameters
    ----------
    function : casadi.Function
        The function, with dense inputs and outputs.
    library : ctypes.CDLL, optional
        The shared library holding its generated C (``compile_library``); None: CasADi's own call.

    Raises
    ------
    ValueError
        For a sparse input or output.
    """

    def __init__(self, function: ca.Function, library: Optional[ctypes.CDLL] = None) -> None:
        for i in range(function.n_in()):
            if not function.sparsity_in(i).is_dense():
                raise ValueError(f"{function.name()}: input {function.name_in(i)} is sparse; NativeFunction "
                                 f"takes dense arguments only")
        for i in range(function.n_out()):
            if not function.sparsity_out(i).is_dense():
                raise ValueError(f"{function.name()}: output {function.name_out(i)} is sparse")
        self.function = function
        self.inputs: list[npt.NDArray[np.float64]] = [np.zeros(function.nnz_in(i)) for i in range(function.n_in())]
        self.outputs: list[npt.NDArray[np.float64]] = [np.zeros(function.nnz_out(i))
                                                       for i in range(function.n_out())]
        self._entry = None
        if library is not None:
            name = function.name()
            # casadi_int is CasADi's default, long long; casadi_real double
            sizes = [ctypes.c_longlong() for _ in range(4)]
            getattr(library, f"{name}_work")(*(ctypes.byref(size) for size in sizes))
            arg_count, res_count, iw_count, w_count = (size.value for size in sizes)
            # the work vectors and pointer arrays live as long as this object: the C code only borrows them
            self._iw = np.zeros(max(iw_count, 1), dtype=np.int64)
            self._w = np.zeros(max(w_count, 1))
            self._arg = (ctypes.c_void_p * max(arg_count, len(self.inputs)))(*(a.ctypes.data for a in self.inputs))
            self._res = (ctypes.c_void_p * max(res_count, len(self.outputs)))(*(a.ctypes.data for a in self.outputs))
            getattr(library, f"{name}_incref")()
            self._memory = getattr(library, f"{name}_checkout")()
            entry = getattr(library, name)
            entry.argtypes = [ctypes.c_void_p] * 4 + [ctypes.c_int]
            entry.restype = ctypes.c_int
            self._entry = entry
            self._call_arguments = (self._arg, self._res, ctypes.c_void_p(self._iw.ctypes.data),
                                    ctypes.c_void_p(self._w.ctypes.data), self._memory)

    def __call__(self) -> None:
        """Evaluate on the input buffers into the output buffers.

        Raises
        ------
        ArithmeticError
            When the compiled function reports an error.
        """
        if self._entry is not None:
            if self._entry(*self._call_arguments) != 0:
                raise ArithmeticError(f"{self.function.name()}: the compiled function reported an error")
            return
        for output, value in zip(self.outputs, self.function.call([a.copy() for a in self.inputs])):
            output[:] = np.asarray(value, dtype=float).ravel(order="F")
