"""Compile CasADi functions to C once and load them as the fast numeric path.

The C source that CasADi generates for a set of functions is compiled with the system C compiler
into a shared library kept in a cache directory (``$SWIM_CACHE_DIR``, else
``$XDG_CACHE_HOME/swim_model``, else ``~/.cache/swim_model``), named by the hash of the source, so
a model is compiled once per machine and rig. Without a C compiler the functions run in CasADi's
virtual machine: the same numbers, several times slower.
"""
from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import tempfile
import warnings
from pathlib import Path

import casadi as ca

COMPILER_FLAGS = ("-O2", "-shared", "-fPIC")


def cache_dir() -> Path:
    """Where compiled models are kept."""
    if os.environ.get("SWIM_CACHE_DIR"):
        return Path(os.environ["SWIM_CACHE_DIR"])
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "swim_model"


def compiled(functions: list[ca.Function], tag: str) -> dict[str, ca.Function]:
    """The functions, compiled to C and loaded (or, without a compiler, as given), by name."""
    compiler = shutil.which(os.environ.get("CC", "gcc"))
    if compiler is None:
        warnings.warn("no C compiler found: swim_model runs its models in CasADi's virtual machine (slower)")
        return {f.name(): f for f in functions}
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
    return {f.name(): ca.external(f.name(), str(library)) for f in functions}
