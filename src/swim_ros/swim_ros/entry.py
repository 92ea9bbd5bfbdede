"""``run_node``: the one ``main()`` of every swim node.

Follows ros2/demos: init (with the Fast DDS profile the node's transport chooses, swim_ros.transport), make the
node, spin; Ctrl-C (SIGINT, SIGTERM) and an external shutdown are a normal stop, wherever in the executor's loop
they land; the context is shut down however the process ends. A node whose construction raises one of
``fatal_errors`` (a bad parameter, a library that does not load) logs the reason as fatal and exits with status 2,
without a traceback.

SIGTERM (also a node's parent-death signal, swim_ros.processes) is taken as Ctrl-C: KeyboardInterrupt in the main
thread. rclpy's own SIGTERM handling alone loses some: its signal thread wakes the executors and only then shuts
the contexts down, so an executor that looks at its context in between waits again, and an idle node (no timer,
no message coming) never stops; about one SIGTERM in a hundred here. SIGINT never had that gap: rclpy passes it on
to Python's handler, which raises KeyboardInterrupt, and now passes SIGTERM on the same way.

The node's DDS teardown is bounded. Fast DDS's participant teardown spins, holding the participant's listener
mutex, while a discovery callback is in flight (eProsima/Fast-DDS#6513); when peers leave at the same moment, as a
whole system stopping does, that callback can starve for good on a busy host, and the process would never end (a
second Ctrl-C cannot help: the spin holds the GIL). A process that has not finished tearing its node down after
DDS_TEARDOWN_TIMEOUT_S dumps every thread's stack to stderr and exits with status 1 (Python's faulthandler, whose
watchdog needs no GIL).
"""
from __future__ import annotations

import faulthandler
import threading
from typing import Callable, Optional, TypeVar

import rclpy
from rclpy.executors import Executor, ExternalShutdownException, SingleThreadedExecutor
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.node import Node

from swim_ros.processes import interrupt_on_sigterm
from swim_ros.transport import TransportChoice

NodeT = TypeVar("NodeT", bound=Node)

#: the exit status of a node that could not start (bad parameters or files): a usage error, as argparse's
FATAL_EXIT_STATUS = 2
#: how long a stopped node's DDS teardown may take before the process dumps its stacks and exits with status 1
#: (module docstring): a teardown takes well under a second, and 5 s stays inside a starter's grace period
#: (swim_ros.processes.STOP_GRACE_S)
DDS_TEARDOWN_TIMEOUT_S = 5.0


def run_node(make_node: Callable[[], NodeT], args: Optional[list[str]] = None, *, name: str,
             fatal_errors: tuple[type[BaseException], ...] = (ValueError,),
             executor: Callable[[], Executor] = SingleThreadedExecutor,
             start: Optional[Callable[[NodeT], object]] = None,
             stop: Optional[Callable[[NodeT], object]] = None,
             transport: Optional[Callable[[], TransportChoice]] = None) -> None:
    """Run one node until SIGINT or shutdown.

    Args:
        make_node: builds the node (after rclpy.init).
        args: the command line (ROS arguments), as rclpy.init takes it.
        name: the logger a fatal start-up error is reported on (the node's name).
        fatal_errors: exceptions from make_node or start that stop the process with FATAL_EXIT_STATUS.
        executor: makes the executor to spin in (single-threaded by default).
        start: called once with the node before spinning (for example a lifecycle node's autostart).
        stop: called with the node however spinning ends, before shutdown (for example to release hardware).
        transport: chooses the node's Fast DDS profile before rclpy.init (swim_ros.transport:
            use_large_message_transport for a node that sends plans, use_real_time_transport for one with a real-time
            loop); None: Fast DDS's defaults.
    """
    owns_process = threading.current_thread() is threading.main_thread()
    if owns_process:
        interrupt_on_sigterm()   # before rclpy.init, so that rclpy's handler passes SIGTERM on to it
    choice = transport() if transport is not None else None
    rclpy.init(args=args)   # this rclpy's init() is not a context manager, hence try/finally
    if choice is not None:
        logger = rclpy.logging.get_logger(name)
        (logger.warning if choice.warning else logger.info)(choice.reason)
    node: Optional[NodeT] = None
    try:
        try:
            node = make_node()
            if start is not None:
                start(node)
        except fatal_errors as err:
            rclpy.logging.get_logger(name).fatal(str(err))
            raise SystemExit(FATAL_EXIT_STATUS) from err
        spinner = executor()
        spinner.add_node(node)
        spinner.spin()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except _rclpy.RCLError:
        _raise_unless_shut_down()
    finally:
        try:
            if node is not None and stop is not None:
                stop(node)
        finally:
            _tear_down(node, bounded=owns_process)


def _tear_down(node: Optional[Node], *, bounded: bool) -> None:
    """Destroy the node (the context's last: its DDS participant goes with it) and shut the context down.

    bounded: the process ends, with its stacks on stderr and status 1, if this takes DDS_TEARDOWN_TIMEOUT_S (module
    docstring); only for the process's own main thread.
    """
    if bounded:
        faulthandler.dump_traceback_later(DDS_TEARDOWN_TIMEOUT_S, exit=True)
    try:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    except _rclpy.RCLError:
        _raise_unless_shut_down()
    finally:
        if bounded:
            faulthandler.cancel_dump_traceback_later()


def _raise_unless_shut_down() -> None:
    """Re-raise the RCLError being handled unless the context is shut down.

    rclpy's SIGINT/SIGTERM handler shuts the context down from its own thread: landing between the executor's check and
    its new wait set, or between try_shutdown's check and its shutdown, it makes those raise where a normal stop was
    meant.
    """
    if rclpy.ok():
        raise
