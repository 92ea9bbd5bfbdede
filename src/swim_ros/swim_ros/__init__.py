"""swim_ros: the ROS boundary every swim node and client shares, and nothing else (no physics).

- ``qos``: the QoS profiles of our topics and the publisher/subscription factories.
- ``entry``: ``run_node``, the one ``main()`` of every node (init, spin, clean stop, exit status 2 on a fatal
  start-up error).
- ``codecs``: between messages and numpy: float64[] fields, stamps.
- ``domains``: ``claim_ros_domain``, a ROS_DOMAIN_ID no other live test or run on this host holds.
- ``calls``: service calls that survive a lost answer (Fast DDS can drop a response sent before the server
  matched the client's response reader).
- ``processes``: ``NodeSpec`` and ``NodeProcess``, how every process we start runs (``ros2 run`` in its own process
  group, stopped by SIGINT, then SIGKILL after a grace period).
- ``realtime``: the real-time means of a periodic process (scheduling policy, locked memory, CPU set, the garbage
  collector between periods), applied where permitted and otherwise refused with the reason.
- ``testing``: for tests only (never imported by a node): the DDS fixtures and fuzz strategies every package's
  tests share.
"""
from swim_ros.exports import lazy_exports

#: the public names by module, each imported on first use
__all__, __getattr__ = lazy_exports(__name__, {
    "calls": ("ActionClient", "CallFailed", "RetryPolicy", "call_service", "send_goal", "goal_result", "cancel_goal",
              "change_lifecycle_state"),
    "codecs": ("MessageError", "float_array", "stamp_of", "joint_state_arrays", "torque_from_command"),
    "domains": ("claim_ros_domain",),
    "entry": ("run_node",),
    "exports": ("lazy_exports",),
    "lifecycle": ("configure_and_activate", "guard_change_state_service"),
    "parameters": ("ParameterSpec", "NodeSettings", "markdown_table"),
    "processes": ("NodeSpec", "NodeProcess"),
    "qos": ("per_period_publisher", "per_period_subscription"),
    "realtime": ("RealtimeSettings", "make_process_realtime", "make_process_ordinary", "PeriodicCollector"),
    "trajectory_messages": ("trajectory_to_message", "trajectory_from_message", "state_from_message"),
    "typestore": ("swim_typestore", "message_definition"),
})
