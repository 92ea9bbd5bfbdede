#!/usr/bin/env bash
# The one setup step of the swim workspace (used by every Makefile target).
#   1. a Python 3.11 virtual environment in .venv (the ros-jazzy-* wheels are cp311 only);
#   2. the pinned dependencies of requirements.lock;
#   3. the wheels' CMake path fix (below);
#   4. `colcon build` of src/ into install/;
#   5. the browser test's tools: Debian's chromium (when missing, as root with apt) and the test page's bundle
#      (npm ci, esbuild) in src/swim_viz/test/browser.
# Each step records what it did in a stamp file and is skipped when its inputs are unchanged,
# so a second run does nothing it need not do.
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
venv=${SWIM_VENV:-$root/.venv}
python=${SWIM_PYTHON:-python3.11}

fail() { echo "setup: error: $*" >&2; exit 1; }
note() { echo "setup: $*"; }
digest() { sha256sum | cut -d' ' -f1; }

# one setup at a time per workspace: two `make` runs at once would build into the same install/
mkdir -p "$root/log"
exec 9>"$root/log/.setup.lock"
flock 9

# --- 0. what the machine must have --------------------------------------------------------
command -v "$python" >/dev/null 2>&1 \
  || fail "no '$python' on PATH; install Python 3.11 (the ROS 2 Jazzy wheels are built for CPython 3.11 only) or set SWIM_PYTHON"
"$python" -c 'import sys; sys.exit(0 if sys.version_info[:2] == (3, 11) else 1)' \
  || fail "'$python' is Python $("$python" -c 'import sys; print("%d.%d" % sys.version_info[:2])'), not 3.11; set SWIM_PYTHON to a Python 3.11"
"$python" -c 'import venv, ensurepip' 2>/dev/null || fail "'$python' lacks the venv/ensurepip modules (Debian: apt-get install python3.11-venv)"
for tool in cmake gcc g++ make; do
  command -v "$tool" >/dev/null 2>&1 || fail "'$tool' not found; it builds swim_interfaces (Debian: apt-get install cmake build-essential)"
done

# --- 1. virtual environment ---------------------------------------------------------------
if [ ! -x "$venv/bin/python" ]; then
  note "creating virtual environment $venv"
  "$python" -m venv "$venv"
fi

# --- 2. pinned dependencies ---------------------------------------------------------------
want=$(cat "$root/requirements.in" "$root/requirements.lock" | digest)
stamp="$venv/.swim-requirements.sha256"
if [ "$(cat "$stamp" 2>/dev/null)" != "$want" ]; then
  note "installing pinned dependencies (requirements.lock)"
  mkdir -p "$root/log"
  pip_log="$root/log/setup-pip.txt"
  { "$venv/bin/python" -m pip install --disable-pip-version-check --upgrade pip==26.3 \
    && "$venv/bin/python" -m pip install --disable-pip-version-check \
         -r "$root/requirements.in" -c "$root/requirements.lock"; } >"$pip_log" 2>&1 \
    || { grep -E '^(ERROR|error)' "$pip_log" >&2 || tail -n 20 "$pip_log" >&2
         fail "pip could not install requirements.in pinned by requirements.lock (is PyPI reachable? full output: $pip_log)"; }
  echo "$want" > "$stamp"
fi

# --- 3. CMake path fix ----------------------------------------------------------------------
# Why: the ros-jazzy-* wheels were built in a manylinux container whose Python lived in
# /opt/python/cp311-cp311, and their exported CMake files (share/*/cmake/*Export.cmake) still
# name that Python's include and site-packages directories. CMake refuses imported targets whose
# include directories do not exist, so building any interface package fails until those paths
# name this environment's own Python headers and site-packages.
py_include=$("$venv/bin/python" -c 'import sysconfig; print(sysconfig.get_paths()["include"])')
py_site=$("$venv/bin/python" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')
[ -f "$py_include/Python.h" ] || fail "no Python.h in $py_include; install the Python 3.11 headers (Debian: python3.11-dev)"
mapfile -t stale < <(grep -rl --include='*.cmake' '/opt/python/cp311-cp311/' "$venv/share" 2>/dev/null || true)
if [ "${#stale[@]}" -gt 0 ]; then
  note "pointing ${#stale[@]} CMake files of the ROS wheels at this environment's Python"
  sed -i \
    -e "s#/opt/python/cp311-cp311/include/python3.11#$py_include#g" \
    -e "s#/opt/python/cp311-cp311/lib/python3.11/site-packages#$py_site#g" \
    "${stale[@]}"
fi

# the browser test's page (step 5): no input of the colcon build (nothing of it is installed), step 5 has its own stamps
browser_rel=src/swim_viz/test/browser
browser_dir=$root/$browser_rel

# --- 4. colcon build --------------------------------------------------------------------------
# shellcheck source=scripts/env.sh
source "$root/scripts/env.sh"
sources=$(cd "$root" && { cat colcon.meta requirements.lock; \
  find src -type f -not -path '*/__pycache__/*' -not -path '*/.*' -not -name '*.pyc' \
    -not -path "$browser_rel/*" -print0 | sort -z | xargs -0 sha256sum; } | digest)
stamp="$root/install/.swim-sources.sha256"
if [ "$(cat "$stamp" 2>/dev/null)" != "$sources" ]; then
  note "colcon build (log: $root/log/latest_build)"
  (cd "$root" && colcon --log-base log build --base-paths src --metas colcon.meta \
      --cmake-args "-DPython3_EXECUTABLE=$venv/bin/python" \
      --event-handlers console_cohesion- summary+ status- >"$root/log/setup-build.txt" 2>&1) \
    || { tail -n 40 "$root/log/setup-build.txt" >&2; fail "colcon build failed (full output: log/setup-build.txt)"; }
  # the vortex wake's numba kernels, compiled into their cache beside the installed module, so that the first
  # process to step a wake does not spend seconds compiling them
  note "compiling the vortex wake's kernels"
  (source "$root/scripts/env.sh" && python -c 'from swim_model.wake import compile_kernels; compile_kernels()') \
    || fail "compiling the vortex wake's kernels failed"
  echo "$sources" > "$stamp"
fi
# --- 5. the browser test's tools -------------------------------------------------------------
# Optional: without them the browser test skips and says why; everything else runs. Debian's chromium is the only
# browser we use (npm packages that download a browser of their own cannot here); the page's npm packages are pinned
# by its package-lock.json and installed without their install scripts (esbuild's only checks its binary).
if ! command -v chromium >/dev/null 2>&1; then
  chromium_failed="$root/log/.setup-chromium-failed"
  if [ "$(id -u)" -eq 0 ] && command -v apt-get >/dev/null 2>&1 && [ ! -f "$chromium_failed" ]; then
    note "installing chromium (Debian) for the browser test (log: $root/log/setup-chromium.txt)"
    # the package lists may be missing or stale on a fresh machine: update them once if the first try fails
    if { DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends chromium \
         || { apt-get update && DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends chromium; }; \
       } >"$root/log/setup-chromium.txt" 2>&1; then
      :
    else
      # not again on every setup: delete the marker to retry
      touch "$chromium_failed"
      note "chromium could not be installed (see log/setup-chromium.txt): the browser test will be skipped"
    fi
  elif [ -f "$chromium_failed" ]; then
    note "no chromium (its install failed, see log/setup-chromium.txt; delete $chromium_failed to retry): the browser test will be skipped"
  else
    note "no chromium (setup installs it only as root with apt-get): the browser test will be skipped"
  fi
fi
if command -v npm >/dev/null 2>&1; then
  want=$(cd "$browser_dir" && cat package.json package-lock.json | digest)
  stamp="$browser_dir/node_modules/.swim-lock.sha256"
  if [ "$(cat "$stamp" 2>/dev/null)" != "$want" ]; then
    note "installing the browser test page's npm packages (package-lock.json)"
    (cd "$browser_dir" && npm ci --ignore-scripts --no-audit --no-fund >"$root/log/setup-npm.txt" 2>&1) \
      || { tail -n 20 "$root/log/setup-npm.txt" >&2
           fail "npm ci failed in $browser_rel (is the npm registry reachable? full output: log/setup-npm.txt)"; }
    echo "$want" > "$stamp"
  fi
  want=$(cd "$browser_dir" && cat package.json package-lock.json index.html page.ts | digest)
  stamp="$browser_dir/dist/.swim-sources.sha256"
  if [ "$(cat "$stamp" 2>/dev/null)" != "$want" ] || [ ! -f "$browser_dir/dist/page.js" ]; then
    note "bundling the browser test's page (esbuild)"
    (cd "$browser_dir" && npm run --silent build >"$root/log/setup-esbuild.txt" 2>&1) \
      || { cat "$root/log/setup-esbuild.txt" >&2; fail "bundling $browser_rel/page.ts failed (log/setup-esbuild.txt)"; }
    echo "$want" > "$stamp"
  fi
else
  note "no npm (Node.js): the browser test's page cannot be built, the browser test will be skipped"
fi
note "ready ($venv, $root/install)"
