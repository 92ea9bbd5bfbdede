#!/usr/bin/env bash
# All tests: every package's own suite through colcon (pytest for the ament_python packages, ctest for
# swim_interfaces), then the workspace tests in tests/ (across packages, over DDS). Exits non-zero when
# any test fails; the last line sums both runs.
set -uo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
# shellcheck source=scripts/env.sh
source scripts/env.sh
export PYTHONDONTWRITEBYTECODE=1

rm -rf build/*/pytest.xml build/*/test_results
# one package at a time: several packages start nodes over DDS, and two such suites at once on this 2-core
# machine make each other's deadlines (ROS domains are apart: swim_ros.domains)
colcon --log-base log test --base-paths src --executor sequential --event-handlers console_direct+ \
  --pytest-args -p no:cacheprovider -q
colcon_status=$?
colcon_summary=$(colcon --log-base log test-result --test-result-base build --all 2>/dev/null | tail -n 1)
colcon --log-base log test-result --test-result-base build >/dev/null 2>&1 || colcon_status=1
echo "colcon test-result: $colcon_summary"

python -m pytest tests -q -p no:cacheprovider --junitxml=log/workspace-tests.xml
pytest_status=$?

python - "$colcon_summary" log/workspace-tests.xml <<'PY'
import re, sys, xml.etree.ElementTree as ET
m = re.search(r"(\d+) tests?, (\d+) errors?, (\d+) failures?, (\d+) skipped", sys.argv[1])
if m is None:
    print(f"run_tests.sh: colcon's summary not understood: {sys.argv[1]!r}", file=sys.stderr)
total, errors, failures, skipped = (int(g) for g in m.groups()) if m else (0, 0, 0, 0)
suite = ET.parse(sys.argv[2]).getroot()
suite = suite if suite.tag == "testsuite" else suite[0]
ws = {k: int(suite.get(k, 0)) for k in ("tests", "errors", "failures", "skipped")}
failed = errors + failures + ws["errors"] + ws["failures"]
passed = total + ws["tests"] - failed - skipped - ws["skipped"]
print(f"tests: {passed} passed, {failed} failed, {skipped + ws['skipped']} skipped")
PY
[ "$colcon_status" -eq 0 ] && [ "$pytest_status" -eq 0 ]
