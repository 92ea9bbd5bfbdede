"""A ROS domain of the process's own, for tests, the demo, the experiments and the benchmarks.

Two such processes running at once (colcon testing packages in parallel, a flake hunter, a demo in another
shell) must never share a ROS_DOMAIN_ID, or their nodes discover each other. ``claim_ros_domain`` takes an exclusive
lock on one file per domain under the system's temporary directory and keeps it for the life of the process;
the operating system releases it when the process ends, however it ends.
"""
from __future__ import annotations

import fcntl
import os
import random
import tempfile
from pathlib import Path
from typing import IO

#: the domains tests use, and those runs (swim-demo, swim-experiments, benchmarks) use: a run never meets a test
TEST_DOMAINS = range(1, 101)
RUN_DOMAINS = range(101, 201)
_held: dict[int, IO[str]] = {}


def claim_ros_domain(domains: range = TEST_DOMAINS, lock_dir: Path | None = None) -> int:
    """A domain in ``domains`` no other live process has claimed, exported as ROS_DOMAIN_ID with discovery on localhost.

    The same domain for every call in one process. Raises RuntimeError if all are taken.
    """
    if _held:
        return next(iter(_held))
    directory = lock_dir or Path(tempfile.gettempdir()) / "swim_ros_domains"
    directory.mkdir(parents=True, exist_ok=True)
    candidates = list(domains)
    random.Random(os.getpid()).shuffle(candidates)
    for domain in candidates:
        handle = open(directory / f"{domain}.lock", "w")
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            handle.close()
            continue
        handle.write(f"{os.getpid()}\n")
        handle.flush()
        _held[domain] = handle
        os.environ["ROS_DOMAIN_ID"] = str(domain)
        os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
        return domain
    raise RuntimeError(f"every ROS domain in {domains} is claimed by a live process (locks in {directory})")


def run_domain() -> int:
    """The ROS domain of a run (swim-demo, swim-experiments, a benchmark).

    The user's ROS_DOMAIN_ID if set, else one claimed in RUN_DOMAINS; discovery on localhost unless the user chose
    otherwise.
    """
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    if os.environ.get("ROS_DOMAIN_ID"):
        return int(os.environ["ROS_DOMAIN_ID"])
    return claim_ros_domain(RUN_DOMAINS)
