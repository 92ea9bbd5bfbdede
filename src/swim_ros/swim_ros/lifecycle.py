"""What swim's lifecycle nodes share.

A change_state service that answers a transition the state does not have, and the one-command start (configure, then
activate) behind their autostart parameter.
"""
from __future__ import annotations

from lifecycle_msgs.srv import ChangeState
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.lifecycle import Node as LifecycleNode
from rclpy.lifecycle import TransitionCallbackReturn


def guard_change_state_service(node: LifecycleNode) -> None:
    """Make node's change_state service answer success=False for a transition the state does not have.

    The rclpy 7.1.6 handler raises out of the change_state service for such a transition (activate while unconfigured),
    which ends spin() and the process.

    Why through a private attribute: there is no public way in this rclpy. The crash is ros2/rclpy#1209; its
    fix (ros2/rclpy#1319: __change_state catches the RCLError and returns ERROR) is in rclpy 8 (rolling), not
    in Jazzy's 7.1.x, the newest on PyPI being 7.1.6. The public alternative, LifecycleNode(...,
    enable_communication_interface=False) and our own lifecycle services around the public trigger_*
    methods, would mean serving change_state, get_state (7.1 has no public current-state getter: we would
    track it ourselves), get_available_states, get_available_transitions, get_transition_graph and the
    transition_event topic by hand: far more to get wrong than wrapping one callback. On an rclpy that has
    the fix, or no such attribute, this does nothing harmful: the wrapper only catches what escapes.
    """
    service = getattr(node, "_service_change_state", None)
    if service is None:
        return
    inner = service.callback

    def change_state(request: ChangeState.Request, response: ChangeState.Response) -> ChangeState.Response:
        try:
            return inner(request, response)
        except _rclpy.RCLError as err:
            node.get_logger().warning(f"transition {request.transition.id} '{request.transition.label}' "
                                      f"refused: {err}")
            response.success = False
            return response

    service.callback = change_state


def configure_and_activate(node: LifecycleNode) -> bool:
    """Configure, then activate (each only if the one before succeeded); True when the node ends active."""
    return (node.trigger_configure() == TransitionCallbackReturn.SUCCESS
            and node.trigger_activate() == TransitionCallbackReturn.SUCCESS)
