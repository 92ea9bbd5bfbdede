"""The stall witness in real processes: each CPU's witness gets its real-time means, and a witness held up (SIGSTOP,
then SIGCONT) writes down a stall as long as the hold, on its own CPU only."""
import os
import signal
import time

import pytest

from swim_ros.testing.stall_witness import PERIOD_S, REPORT_LATENESS_S, StallWitness

pytestmark = pytest.mark.skipif(os.geteuid() != 0, reason="the witness's real-time means need root here (CI runs as "
                                                          "root)")

#: how long the test holds one witness up, s: well past REPORT_LATENESS_S
HOLD_S = 0.15


def test_a_witness_held_up_writes_down_a_stall_as_long_as_the_hold(tmp_path):
    with StallWitness(tmp_path) as witness:
        assert witness.refused is None
        assert len(witness.pids) == len(os.sched_getaffinity(0))
        held = witness.pids[0]
        time.sleep(0.2)
        os.kill(held, signal.SIGSTOP)
        time.sleep(HOLD_S)
        os.kill(held, signal.SIGCONT)
        time.sleep(0.2)
    held_cpu = min(os.sched_getaffinity(0))
    longest = max((stall.lateness_s for stall in witness.stalls if stall.cpu == held_cpu), default=0.0)
    # stopped at most a period before its next wake-up, and held from one kill's return to the other's
    assert HOLD_S - 2 * PERIOD_S <= longest < HOLD_S + 0.5
    assert witness.worst_s >= longest > REPORT_LATENESS_S
