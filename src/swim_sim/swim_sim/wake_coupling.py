"""sim_node's ``wake.*`` parameters for the vortex wake's coupling. No ROS.

The coupling itself is swim_model.wake_coupling, which this module re-exports for swim_sim's users.
"""
from __future__ import annotations

from swim_model.wake import WakeParameters
from swim_model.wake_coupling import (
    FORCE_LIMIT_N,
    MOMENT_LIMIT_N_M,
    WakeCoupling,
    WakeCouplingParameters,
    WakeStatistics,
    WakeVortices,
)

__all__ = ["FORCE_LIMIT_N", "MOMENT_LIMIT_N_M", "WakeCoupling", "WakeCouplingParameters", "WakeStatistics",
           "WakeVortices", "parameter_defaults", "parameters_from_values"]


def parameter_defaults() -> dict[str, int | float]:
    """sim_node's ``wake.*`` numerical parameters and their defaults (the wake is on with sim_node's flow "wake").

    ``max_vortex_count`` 0 means never merge; ``critical_leading_edge_suction`` 0 means the attached flow's whole
    leading-edge suction; the water density is the rig's.
    """
    wake = WakeParameters()
    return {"core_radius_m": wake.core_radius_m,
            "shed_distance_fraction": wake.shed_distance_fraction, "min_shed_distance_m": wake.min_shed_distance_m,
            "max_vortex_count": wake.max_vortex_count or 0, "protected_vortex_count": wake.protected_vortex_count,
            "opposite_sign_merge_penalty": wake.opposite_sign_merge_penalty,
            "surface_absorption_gap_m": wake.surface_absorption_gap_m,
            "kinematic_viscosity_m2_s": wake.kinematic_viscosity_m2_s,
            "critical_leading_edge_suction": wake.critical_leading_edge_suction or 0.0,
            "force_limit_n": FORCE_LIMIT_N, "moment_limit_n_m": MOMENT_LIMIT_N_M}


def parameters_from_values(values: dict[str, int | float]) -> WakeCouplingParameters:
    """WakeCouplingParameters from sim_node's ``wake.*`` values (keys of parameter_defaults; StateError if bad)."""
    wake = WakeParameters(core_radius_m=float(values["core_radius_m"]),
                          shed_distance_fraction=float(values["shed_distance_fraction"]),
                          min_shed_distance_m=float(values["min_shed_distance_m"]),
                          max_vortex_count=int(values["max_vortex_count"]) or None,
                          protected_vortex_count=int(values["protected_vortex_count"]),
                          opposite_sign_merge_penalty=float(values["opposite_sign_merge_penalty"]),
                          surface_absorption_gap_m=float(values["surface_absorption_gap_m"]),
                          kinematic_viscosity_m2_s=float(values["kinematic_viscosity_m2_s"]),
                          critical_leading_edge_suction=float(values["critical_leading_edge_suction"]) or None)
    return WakeCouplingParameters(wake=wake, force_limit_n=float(values["force_limit_n"]),
                                  moment_limit_n_m=float(values["moment_limit_n_m"]))
