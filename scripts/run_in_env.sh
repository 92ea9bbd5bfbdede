#!/usr/bin/env bash
# Run a command inside the swim workspace's environment (venv + ROS prefix + install/).
set -euo pipefail
# shellcheck source=scripts/env.sh
source "$(dirname "${BASH_SOURCE[0]}")/env.sh"
exec "$@"
