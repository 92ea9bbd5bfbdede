"""Messages of synthetic runs as the nodes publish them, serialized by rosbags for the recorder's BagWriter (no
ROS): tracker_node's tracking_state and bridge_node's /diagnostics."""
import numpy as np


def tracking_state_cdr(store, joint_names, stamp_ns: int, plan_time_s: float, feedback, reference,
                       output_torques=(0.0, 0.0), saturated=(False, False), sliding_mode_enabled=True) -> bytes:
    """A swim_interfaces/TrackingState of one period: measured positions feedback, desired positions reference."""
    types = store.types
    Time, Duration = types["builtin_interfaces/msg/Time"], types["builtin_interfaces/msg/Duration"]

    def point(positions):
        empty = np.zeros(0)
        return types["trajectory_msgs/msg/JointTrajectoryPoint"](np.array(positions, float),
                                                                 np.zeros(len(joint_names)), empty, empty,
                                                                 Duration(0, 0))
    error = np.array(reference, float) - np.array(feedback, float)
    message = types["swim_interfaces/msg/TrackingState"](
        types["std_msgs/msg/Header"](Time(stamp_ns // 1_000_000_000, stamp_ns % 1_000_000_000), ""),
        list(joint_names), point(reference), point(feedback), point(error), np.array(output_torques, float),
        np.zeros(2), np.array(saturated, bool), plan_time_s, 1.0, 0, sliding_mode_enabled, np.zeros(0), np.zeros(0))
    return bytes(store.serialize_cdr(message, message.__msgtype__))


def diagnostics_cdr(store, name: str, faults: str, overruns: int, sec: int, timing: dict | None = None) -> bytes:
    """A diagnostic_msgs/DiagnosticArray as bridge_node publishes it (with timing: those keys and values too)."""
    types = store.types
    Array, Status, KeyValue = (types[f"diagnostic_msgs/msg/{t}"] for t in ("DiagnosticArray", "DiagnosticStatus",
                                                                            "KeyValue"))
    Header, Time = types["std_msgs/msg/Header"], types["builtin_interfaces/msg/Time"]
    values = [KeyValue(key="faults", value=faults), KeyValue(key="overruns", value=str(overruns))]
    values += [KeyValue(key=key, value=value) for key, value in (timing or {}).items()]
    status = Status(level=0, name=f"/{name}: I/O loop", message="", hardware_id="emulated", values=values)
    array = Array(header=Header(stamp=Time(sec=sec, nanosec=0), frame_id=""), status=[status])
    return bytes(store.serialize_cdr(array, "diagnostic_msgs/msg/DiagnosticArray"))
