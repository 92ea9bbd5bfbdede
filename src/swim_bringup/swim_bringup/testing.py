"""The sets' parameter files for tests over DDS on a host that other work shares.

A machine that runs only the rig keeps bridge_node's overrun latch (3 late periods in a row) and tracker_node's
stale-state limit (200 ms) as shipped. On this 2-core test host the other builds and tests keep both cores busy: a
process stalls for up to 0.6 s and the bridge's SCHED_FIFO loop is late several times a minute, so with the
shipped limits a set's run ends on the host's stalls rather than on what its test checks. The tests of the latch
and the limit themselves (swim_hw_bridge's test_bridge_node, swim_controller's test_tracker_node) run them as
shipped.
"""
from __future__ import annotations

import shutil
from pathlib import Path

import yaml

from swim_bringup.system import config_dir

#: late periods in a row that latch the bridge's OVERRUN fault on a shared host: 0.4 s of 8 ms periods, beyond the
#: host's stalls
SHARED_HOST_OVERRUN_LIMIT = 50
#: tracker_node's stale limit on a shared host, periods of 8 ms: 2 s, beyond the host's 0.6 s stalls
SHARED_HOST_STALE_AFTER_PERIODS = 250


def shared_host_config(pipeline: str, folder: Path) -> Path:
    """A copy of the pipeline's parameter files with the latch and the limit raised for a shared host.

    Parameters
    ----------
    pipeline : str
        "realistic" or "paper" (``swim_bringup.system.config_dir``).
    folder : Path
        Where the copy goes, as folder/config; the folder exists, folder/config does not.

    Returns
    -------
    Path
        folder/config, to pass as ``--config`` or to ``closed_loop_specs``.

    Raises
    ------
    ValueError
        For another pipeline.
    """
    config = Path(shutil.copytree(config_dir(pipeline), folder / "config"))
    for name, node, parameter, value in (
            ("bridge.yaml", "bridge_node", "overrun_limit", SHARED_HOST_OVERRUN_LIMIT),
            ("tracker.yaml", "tracker_node", "stale_after_periods", SHARED_HOST_STALE_AFTER_PERIODS)):
        parameters = yaml.safe_load((config / name).read_text())
        parameters[node]["ros__parameters"][parameter] = value
        (config / name).write_text(yaml.safe_dump(parameters))
    return config
