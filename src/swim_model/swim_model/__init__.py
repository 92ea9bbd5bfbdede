"""swim_model: the physics of the swimming machine (Saimek & Li, IJRR 2004), with no ROS imports.

Public API:
    load_rig(path=None) -> RigParameters            rig parameters in SI (config/rig.yaml by default)
    JoukowskiFoil(chord_m, thickness_m, span_m)     the foil; .added_mass(rho_kg_m3) -> AddedMass
    VehicleModel(rig, constrained, flow="ideal")    Mm, Cm, forward/inverse dynamics, energy, momentum;
                                                    flow="circulatory" adds swim_model.flow's force and lag states
    SinusoidalGait, simulate_gait                   shape-driven swimming
    Wake(foil, WakeParameters()).step(dt, pose, nu) free-vortex wake: the vortical force the ideal model leaves out
    CirculatoryFlow, FlowParameters                 reduced-order circulatory flow (lift lag, suction, drag, stall)
    oscillating_foil(foil, ...)                     the towed-foil experiment on the reduced model or the wake
"""
from swim_model.errors import FlowModelError, FoilGeometryError, RigConfigError, StateError, SwimModelError
from swim_model.flow import CirculatoryFlow, FlowParameters, OscillatingFoilResult, oscillating_foil
from swim_model.gait import ShapeDrivenRun, SinusoidalGait, simulate_gait
from swim_model.joukowski import AddedMass, JoukowskiFoil
from swim_model.rig import RigParameters, load_rig
from swim_model.vehicle import VehicleModel
from swim_model.wake import Wake, WakeForce, WakeParameters

MODEL_VERSION = "1"  # bump when the equations change: primitive libraries record it

__all__ = [
    "AddedMass", "CirculatoryFlow", "FlowModelError", "FlowParameters", "FoilGeometryError", "JoukowskiFoil",
    "MODEL_VERSION", "OscillatingFoilResult", "RigConfigError", "RigParameters", "ShapeDrivenRun", "SinusoidalGait",
    "StateError", "SwimModelError", "VehicleModel", "load_rig", "oscillating_foil", "Wake", "WakeForce",
    "WakeParameters", "simulate_gait",
]
