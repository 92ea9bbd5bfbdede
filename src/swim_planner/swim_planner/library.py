"""The primitive library on disk: a manifest and one array file per primitive.

Layout of a library directory::

    manifest.json              format version, rig digest, model version, flow model, creation time, solver
                               settings, the LQ weights the stored gains were computed with, and per
                               primitive: its spec, index J, effort, solver status, solve time, whether it has
                               gains, a cruise's mean speed, the array file's name and SHA-256
    primitives/<file>.npz      time_s, q, qdot, foil_acceleration, torque (fine collocation grid), lag (the
                               flow's lag states, circulatory flow only), and riccati P (N, n, n) and
                               riccati_input_gain G'P (N, 2, n) for the tracker
    primitives/<file>.disturbance.npz
                               circulatory flow only, once measured: disturbance_bound_n_m (N,), the sliding
                               mode's bound D(t) on the primitive's samples (swim_planner.disturbance), recorded in
                               the manifest with the SHA-256 of the motion it was measured along

A library is made with one flow model of swim_model (``FLOW_MODELS``: "ideal", the paper's, or "circulatory"),
recorded in its manifest; a format-2 manifest predates the choice and is the ideal model's. A primitive without a
stored D(t) (an ideal-flow one, or any of a format-3 library) leaves the tracker its constant bound.

Loading refuses, with a LibraryError naming the cause: a missing or unparsable manifest, another format
version, a library built for other rig parameters, another model version or another flow model than the one
asked for, and an array file that is missing, truncated or altered (its SHA-256 differs from the manifest's).
"""
from __future__ import annotations

import dataclasses
import datetime
import hashlib
import io
import json
import os
import re
import threading
from pathlib import Path
from typing import Any, Iterable, Iterator, Optional

import numpy as np

from swim_control.riccati import LqrWeights, TrackingGains
from swim_model import MODEL_VERSION, RigParameters
from swim_model.flow import FLOW_MODELS
from swim_planner.disturbance import wake_record
from swim_planner.errors import LibraryError
from swim_planner.primitives import Primitive, PrimitiveSpec, PrimitiveType, SolverSettings, cruise_mean_speed_m_s

FORMAT_VERSION = 4   # 4: the sliding mode's bound D(t); 3: the flow model and the lag states; 2: tracking gains
READABLE_FORMAT_VERSIONS = (2, 3, 4)
#: the flow model of a format-2 library: it was made before the choice existed, with the paper's model
FORMAT_2_FLOW_MODEL = "ideal"
MANIFEST = "manifest.json"
ARRAYS = ("time_s", "q", "qdot", "foil_acceleration", "torque")
LAG_ARRAY = "lag"
GAIN_ARRAYS = ("riccati", "riccati_input_gain")
DISTURBANCE_ARRAY = "disturbance_bound_n_m"
#: the manifest's record of a primitive's D(t) (its file, SHA-256s and how it was measured)
DISTURBANCE_RECORD = "disturbance_bound"


def check_flow_model(flow_model: str) -> str:
    """Check a flow model's name.

    Parameters
    ----------
    flow_model : str
        The name asked for.

    Returns
    -------
    str
        flow_model, one of swim_model's FLOW_MODELS.

    Raises
    ------
    LibraryError
        If it is not one of them (naming them).
    """
    if flow_model not in FLOW_MODELS:
        raise LibraryError(f"unknown flow model {flow_model!r}: one of {', '.join(FLOW_MODELS)}")
    return flow_model


def _file_name(primitive_id: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "__", primitive_id) + ".npz"


def _spec_to_json(spec: PrimitiveSpec) -> dict:
    data = dataclasses.asdict(spec)
    data["primitive_type"] = spec.primitive_type.value
    return data


def _spec_from_json(data: dict) -> PrimitiveSpec:
    return PrimitiveSpec(**{**data, "primitive_type": PrimitiveType(data["primitive_type"])})


def _disturbance_file_name(primitive_id: str) -> str:
    return _file_name(primitive_id).removesuffix(".npz") + ".disturbance.npz"


def motion_digest(primitive: Primitive) -> str:
    """The SHA-256 of a primitive's motion: what its D(t) was measured along.

    Parameters
    ----------
    primitive : Primitive
        The primitive (its times, q, qdot and lag states are hashed).

    Returns
    -------
    str
        The hex digest.
    """
    digest = hashlib.sha256()
    for array in (primitive.time_s, primitive.q, primitive.qdot, *([] if primitive.lag is None else [primitive.lag])):
        digest.update(np.ascontiguousarray(array, dtype=np.float64).tobytes())
    return digest.hexdigest()


def _encode_arrays(primitive: Primitive) -> bytes:
    buffer = io.BytesIO()
    arrays = {name: getattr(primitive, name) for name in ARRAYS}
    if primitive.lag is not None:
        arrays[LAG_ARRAY] = primitive.lag
    if primitive.gains is not None:
        arrays.update(riccati=primitive.gains.riccati, riccati_input_gain=primitive.gains.riccati_input_gain)
    np.savez(buffer, **arrays)
    return buffer.getvalue()


class PrimitiveLibrary:
    """A library directory: write primitives into it, read them back verified (module docstring).

    Parameters
    ----------
    path : str or Path
        The library's directory.
    rig : RigParameters
        The rig the primitives are for (its digest is recorded).
    solver : SolverSettings, optional
        The settings the primitives are solved with.
    lqr_weights : LqrWeights, optional
        The weights the stored gains are computed with.
    flow_model : str, optional
        The flow model the primitives are solved with: "ideal" or "circulatory".

    Raises
    ------
    LibraryError
        If the flow model is unknown.
    """

    def __init__(self, path: str | Path, rig: RigParameters, solver: SolverSettings = SolverSettings(),
                 lqr_weights: LqrWeights = LqrWeights(), flow_model: str = "ideal") -> None:
        self.path = Path(path)
        self.rig = rig
        self.flow_model = check_flow_model(flow_model)
        self.solver = solver
        self.lqr_weights = lqr_weights
        self._entries: dict[str, dict] = {}
        self._cache: dict[str, Primitive] = {}
        self._bounds: dict[str, np.ndarray] = {}
        self._read_lock = threading.Lock()   # several planner threads may ask for one primitive at once

    # ----- writing -------------------------------------------------------------------------------
    @classmethod
    def create_or_open(cls, path: str | Path, rig: RigParameters, solver: SolverSettings = SolverSettings(),
                       lqr_weights: Optional[LqrWeights] = None, flow_model: str = "ideal") -> "PrimitiveLibrary":
        """Open an existing library for adding to it (resuming a build), or start a new one.

        Parameters
        ----------
        path : str or Path
            The library's directory.
        rig : RigParameters
            The rig the primitives are for.
        solver : SolverSettings, optional
            The settings new primitives are solved with.
        lqr_weights : LqrWeights, optional
            The weights gains are to be computed with (None: keep the library's own); primitives whose stored
            gains were computed with other weights then report ``needs_gains``.
        flow_model : str, optional
            The model the primitives are solved with; an existing library of another is refused.

        Returns
        -------
        PrimitiveLibrary
            The library, its manifest written if new.

        Raises
        ------
        LibraryError
            If an existing library cannot be loaded for this rig and flow model (``load``).
        """
        if (Path(path) / MANIFEST).exists():
            library = cls.load(path, rig, flow_model)
            library.solver = solver
            if lqr_weights is not None:
                library.lqr_weights = lqr_weights
            return library
        library = cls(path, rig, solver, lqr_weights or LqrWeights(), flow_model)
        library._write_manifest()
        return library

    def needs_gains(self, primitive_id: str) -> bool:
        """Whether a primitive lacks stored gains for the library's LQ weights.

        True if it has no stored gains, or gains computed with other weights; LibraryError if no primitive of that id
        is in the library.

        Parameters
        ----------
        primitive_id : str
            The primitive whose gains are asked about.
        """
        record = self.entry(primitive_id)
        stored = record.get("gains_lqr_weights")
        if not record.get("has_gains") or not isinstance(stored, dict):
            return True
        try:    # a field the record lacks has its default: the gains were computed as with it
            return LqrWeights(**stored) != self.lqr_weights
        except TypeError:   # a field this version does not know
            return True

    def add(self, primitive: Primitive) -> None:
        """Store one primitive: its array file first, then the manifest, each replaced atomically.

        A stored D(t) is kept if the primitive's motion is the one it was measured along (new gains), else dropped.

        Parameters
        ----------
        primitive : Primitive
            The primitive, of the library's flow model.

        Raises
        ------
        LibraryError
            If its lag states do not fit the library's flow model.
        """
        spec = primitive.spec
        if (primitive.lag is not None) != (self.flow_model == "circulatory"):
            raise LibraryError(f"'{spec.primitive_id}' {'has' if primitive.lag is not None else 'has no'} lag "
                               f"states: not a primitive of this {self.flow_model}-flow library")
        previous = self._entries.get(spec.primitive_id, {})
        payload = _encode_arrays(primitive)
        name = _file_name(spec.primitive_id)
        (self.path / "primitives").mkdir(parents=True, exist_ok=True)
        _atomic_write(self.path / "primitives" / name, payload)
        self._entries[spec.primitive_id] = {
            "spec": _spec_to_json(spec), "file": name, "sha256": hashlib.sha256(payload).hexdigest(),
            "index_j": primitive.index_j, "effort": primitive.effort, "solver_status": primitive.solver_status,
            "solve_time_s": primitive.solve_time_s, "iterations": primitive.iterations,
            "samples": int(len(primitive.time_s)), "has_gains": primitive.gains is not None,
            "gains_lqr_weights": dataclasses.asdict(self.lqr_weights) if primitive.gains is not None else None,
        }
        if spec.primitive_type is PrimitiveType.CRUISE:
            self._entries[spec.primitive_id]["mean_speed_m_s"] = cruise_mean_speed_m_s(primitive)
        bound = previous.get(DISTURBANCE_RECORD)
        if bound is not None and bound.get("motion_sha256") == motion_digest(primitive):
            self._entries[spec.primitive_id][DISTURBANCE_RECORD] = bound
        else:
            self._bounds.pop(spec.primitive_id, None)
        self._cache[spec.primitive_id] = primitive
        self._write_manifest()

    def needs_disturbance_bound(self, primitive_id: str) -> bool:
        """Whether a primitive needs its sliding-mode bound D(t) measured.

        True for a circulatory-flow primitive without a stored D(t), or with one measured in another wake than
        swim_planner.disturbance's; False for ideal-flow ones (they have none).

        Parameters
        ----------
        primitive_id : str
            The primitive whose bound is asked about.

        Raises
        ------
        LibraryError
            For an id the library does not hold.
        """
        if self.flow_model != "circulatory":
            return False
        record = self.entry(primitive_id).get(DISTURBANCE_RECORD)
        return record is None or record.get("wake") != wake_record(self.rig)

    def add_disturbance_bound(self, primitive_id: str, bound_n_m: np.ndarray, measurement: dict) -> None:
        """Store the sliding-mode bound D(t) of a stored circulatory primitive.

        Parameters
        ----------
        primitive_id : str
            The stored primitive the bound belongs to.
        bound_n_m : (N,) array
            D(t), N m, finite and >= 0, on its N samples.
        measurement : dict
            How it was measured (JSON values, kept in the manifest's record).

        Raises
        ------
        LibraryError
            If the library is not circulatory, has no such primitive, or the bound is not N finite values >= 0.
        """
        primitive = self.get(primitive_id)
        bound = np.asarray(bound_n_m, dtype=float)
        if self.flow_model != "circulatory":
            raise LibraryError(f"'{primitive_id}': an {self.flow_model}-flow library stores no disturbance bound")
        if bound.shape != primitive.time_s.shape or not np.all(np.isfinite(bound)) or np.any(bound < 0.0):
            raise LibraryError(f"'{primitive_id}': the disturbance bound must be {len(primitive.time_s)} finite "
                               f"values >= 0 (N m, one a sample), got shape {bound.shape}")
        buffer = io.BytesIO()
        arrays: dict[str, Any] = {DISTURBANCE_ARRAY: bound}
        np.savez(buffer, **arrays)
        payload = buffer.getvalue()
        name = _disturbance_file_name(primitive_id)
        _atomic_write(self.path / "primitives" / name, payload)
        self._entries[primitive_id][DISTURBANCE_RECORD] = {
            **measurement, "file": name, "sha256": hashlib.sha256(payload).hexdigest(),
            "motion_sha256": motion_digest(primitive)}
        self._bounds[primitive_id] = bound.copy()
        self._write_manifest()

    def _write_manifest(self) -> None:
        self.path.mkdir(parents=True, exist_ok=True)
        manifest = {
            "format_version": FORMAT_VERSION,
            "rig_digest": self.rig.digest(),
            "model_version": MODEL_VERSION,
            "flow_model": self.flow_model,
            "created": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "solver": dataclasses.asdict(self.solver),
            "lqr_weights": dataclasses.asdict(self.lqr_weights),
            "primitives": self._entries,
        }
        _atomic_write(self.path / MANIFEST, json.dumps(manifest, indent=1, sort_keys=True).encode())

    # ----- reading -------------------------------------------------------------------------------
    @classmethod
    def load(cls, path: str | Path, rig: RigParameters, flow_model: Optional[str] = "ideal") -> "PrimitiveLibrary":
        """Open a library, checking its format, rig, model and flow model (arrays are verified as they are read).

        Parameters
        ----------
        path : str or Path
            The library's directory.
        rig : RigParameters
            The rig it must have been built for.
        flow_model : str or None, optional
            The flow model the library must have been made with (swim_model's FLOW_MODELS); None takes the
            library's own, whichever it is (to list or show it).

        Returns
        -------
        PrimitiveLibrary
            The library.

        Raises
        ------
        LibraryError
            For a missing or unparsable manifest, another format version, another rig, model version or flow
            model, or unknown settings (module docstring).
        """
        directory = Path(path)
        try:
            manifest = json.loads((directory / MANIFEST).read_text())
        except FileNotFoundError as err:
            raise LibraryError(f"no primitive library at {directory} (no {MANIFEST}); build one with "
                               f"`swim-primitives build {directory}`") from err
        except (OSError, ValueError) as err:
            raise LibraryError(f"{directory / MANIFEST} is unreadable or not JSON: {err}") from err
        found = manifest.get("format_version") if isinstance(manifest, dict) else None
        if found not in READABLE_FORMAT_VERSIONS:
            raise LibraryError(f"{directory}: library format {found!r}, this planner reads formats "
                               f"{', '.join(map(str, READABLE_FORMAT_VERSIONS))}")
        stored_flow = manifest.get("flow_model") if found != 2 else FORMAT_2_FLOW_MODEL
        if stored_flow not in FLOW_MODELS:
            raise LibraryError(f"{directory / MANIFEST}: unknown flow model {stored_flow!r}")
        if flow_model is not None and stored_flow != check_flow_model(flow_model):
            raise LibraryError(f"{directory} holds primitives of the {stored_flow} flow model, not the {flow_model} "
                               f"one asked for; use a library built with `swim-primitives build --flow {flow_model}`")
        if manifest.get("rig_digest") != rig.digest():
            raise LibraryError(f"{directory} was built for other rig parameters (digest "
                               f"{str(manifest.get('rig_digest'))[:12]}..., this rig {rig.digest()[:12]}...); "
                               "rebuild it for this rig")
        if manifest.get("model_version") != MODEL_VERSION:
            raise LibraryError(f"{directory} was built with swim_model version {manifest.get('model_version')!r}, "
                               f"this is version {MODEL_VERSION}; rebuild it")
        try:
            # a manifest without a derivatives setting (the shipped library's) was solved with CasADi's own AD
            solver = SolverSettings(**{"derivatives": "casadi", **manifest.get("solver", {})})
            library = cls(directory, rig, solver, LqrWeights(**manifest.get("lqr_weights", {})), stored_flow)
        except (TypeError, ValueError) as err:
            raise LibraryError(f"{directory / MANIFEST}: unknown solver or LQR setting: {err}") from err
        entries = manifest.get("primitives")
        if not isinstance(entries, dict):
            raise LibraryError(f"{directory / MANIFEST}: 'primitives' must be a mapping")
        library._entries = entries
        return library

    def ids(self) -> list[str]:
        """The library's primitive ids.

        Returns
        -------
        list of str
            Sorted.
        """
        return sorted(self._entries)

    def __contains__(self, primitive_id: str) -> bool:
        """Whether the library holds a primitive of this id."""
        return primitive_id in self._entries

    def __len__(self) -> int:
        """The number of primitives in the library."""
        return len(self._entries)

    def entry(self, primitive_id: str) -> dict:
        """The manifest's record of one primitive.

        Parameters
        ----------
        primitive_id : str
            The primitive's id, as the manifest keys it.

        Returns
        -------
        dict
            Its record (module docstring).

        Raises
        ------
        LibraryError
            If the library has no such primitive.
        """
        try:
            return self._entries[primitive_id]
        except KeyError:
            raise LibraryError(f"no primitive '{primitive_id}' in {self.path}") from None

    def spec(self, primitive_id: str) -> PrimitiveSpec:
        """The spec of one primitive, from the manifest (no array file is read).

        Parameters
        ----------
        primitive_id : str
            The primitive whose spec is read.

        Returns
        -------
        PrimitiveSpec
            What it is.

        Raises
        ------
        LibraryError
            As ``entry``.
        """
        return _spec_from_json(self.entry(primitive_id)["spec"])

    def get(self, primitive_id: str) -> Primitive:
        """Read one primitive, verifying its array file against the manifest (once; thread-safe).

        Parameters
        ----------
        primitive_id : str
            The primitive to read.

        Returns
        -------
        Primitive
            Its samples, and its gains if stored for the library's weights.

        Raises
        ------
        LibraryError
            If there is no such primitive, or its array file is missing, altered or not a valid array file.
        """
        with self._read_lock:
            if primitive_id not in self._cache:
                self._cache[primitive_id] = self._read(primitive_id)
            return self._cache[primitive_id]

    def _read(self, primitive_id: str) -> Primitive:
        record = self.entry(primitive_id)
        file = self.path / "primitives" / record["file"]
        try:
            payload = file.read_bytes()
        except OSError as err:
            raise LibraryError(f"{file}: cannot read the arrays of '{primitive_id}': {err.strerror}") from err
        if hashlib.sha256(payload).hexdigest() != record["sha256"]:
            raise LibraryError(f"{file} is corrupt or truncated (SHA-256 differs from the manifest); "
                               f"rebuild '{primitive_id}'")
        try:
            with np.load(io.BytesIO(payload)) as arrays:
                data = {name: np.array(arrays[name]) for name in ARRAYS}
                if self.flow_model == "circulatory":
                    data[LAG_ARRAY] = np.array(arrays[LAG_ARRAY])
                gains = None
                if not self.needs_gains(primitive_id):
                    gains = TrackingGains(riccati=np.array(arrays["riccati"]),
                                          riccati_input_gain=np.array(arrays["riccati_input_gain"]))
        except (OSError, ValueError, KeyError) as err:
            raise LibraryError(f"{file}: not a valid primitive array file: {err}") from err
        return Primitive(spec=self.spec(primitive_id), index_j=record["index_j"], effort=record["effort"],
                         solver_status=record["solver_status"], solve_time_s=record["solve_time_s"],
                         iterations=record["iterations"], gains=gains, **data)

    def disturbance_bound(self, primitive_id: str) -> Optional[np.ndarray]:
        """The stored sliding-mode bound D(t) of a primitive, verified against the manifest (read once).

        Parameters
        ----------
        primitive_id : str
            The primitive whose D(t) is read.

        Returns
        -------
        (N,) array or None
            D(t), N m on its samples; None if it has none (an ideal-flow primitive, a format-3 library, or not
            measured yet).

        Raises
        ------
        LibraryError
            If there is no such primitive, or its file is missing, altered or not a valid array file.
        """
        record = self.entry(primitive_id).get(DISTURBANCE_RECORD)
        if record is None:
            return None
        with self._read_lock:
            if primitive_id not in self._bounds:
                file = self.path / "primitives" / record["file"]
                try:
                    payload = file.read_bytes()
                except OSError as err:
                    raise LibraryError(f"{file}: cannot read the disturbance bound of '{primitive_id}': "
                                       f"{err.strerror}") from err
                if hashlib.sha256(payload).hexdigest() != record["sha256"]:
                    raise LibraryError(f"{file} is corrupt or truncated (SHA-256 differs from the manifest); "
                                       f"measure the disturbance bound of '{primitive_id}' again")
                try:
                    with np.load(io.BytesIO(payload)) as arrays:
                        self._bounds[primitive_id] = np.array(arrays[DISTURBANCE_ARRAY], dtype=float)
                except (OSError, ValueError, KeyError) as err:
                    raise LibraryError(f"{file}: not a valid disturbance-bound file: {err}") from err
            return self._bounds[primitive_id].copy()

    def sample_count(self, primitive_id: str) -> int:
        """The number N of samples in a primitive's arrays (read once and kept, as ``get``; its LibraryError too).

        Parameters
        ----------
        primitive_id : str
            The primitive whose samples are counted.
        """
        return len(self.get(primitive_id).time_s)

    def __iter__(self) -> Iterator[Primitive]:
        """Every primitive, read and verified, in id order."""
        return (self.get(i) for i in self.ids())

    def digest(self) -> str:
        """The SHA-256 over the manifest's primitive records: names the library a plan came from.

        Returns
        -------
        str
            The hex digest.
        """
        return hashlib.sha256(json.dumps(self._entries, sort_keys=True).encode()).hexdigest()


def _atomic_write(path: Path, payload: bytes) -> None:
    partial = path.with_name(f".{path.name}.{os.getpid()}.partial")
    partial.write_bytes(payload)
    partial.replace(path)


def verify_all(library: PrimitiveLibrary) -> Iterable[str]:
    """Read every primitive and its stored D(t), verifying each.

    Parameters
    ----------
    library : PrimitiveLibrary
        The library.

    Yields
    ------
    str
        The id of each primitive read.

    Raises
    ------
    LibraryError
        On the first bad one.
    """
    for primitive_id in library.ids():
        library.get(primitive_id)
        library.disturbance_bound(primitive_id)
        yield primitive_id
