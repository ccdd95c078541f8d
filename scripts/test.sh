#!/usr/bin/env bash
# The whole check: installs what the tests need, then lint, types and the test suite.
# Usage: bash scripts/test.sh [pytest arguments]
set -euo pipefail
cd "$(dirname "$0")/.."

# Debian packages used by tests that talk to real third-party programs.
debian_packages=(socat indi-bin chromium wrk)
missing=()
for pkg in "${debian_packages[@]}"; do
  dpkg -s "$pkg" >/dev/null 2>&1 || missing+=("$pkg")
done
if ((${#missing[@]})); then
  echo "installing Debian packages: ${missing[*]}"
  sudo_cmd=()
  [ "$(id -u)" = 0 ] || sudo_cmd=(sudo)
  "${sudo_cmd[@]}" apt-get update -qq
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

python="${PYTHON:-python3}"
[ -x .venv/bin/python ] || "$python" -m venv .venv
.venv/bin/python -m pip install -q --disable-pip-version-check -e '.[test]'

echo "== ruff"; .venv/bin/ruff check . && .venv/bin/ruff format --check .
echo "== mypy"; .venv/bin/mypy
# Two workers: CI has two cores and most tests wait on sockets, ptys and paced wires, so two run
# side by side in about 60 % of the time of one. Tests marked `solo` check timing that a busy
# neighbour would distort; they run afterwards in one process (tests/README.md).
# SCOPELINK_TEST_WORKERS=0 runs the first part in one process too; a later -n in "$@" wins.
# pytest exits 5 when a part selects no test (e.g. a path with no solo test): that part passed.
run_part() { .venv/bin/pytest "$@" || { status=$?; [ "$status" = 5 ] || exit "$status"; }; }
echo "== pytest (parallel)"; run_part -n "${SCOPELINK_TEST_WORKERS:-2}" --dist loadfile -m "not solo" "$@"
echo "== pytest (solo)"; run_part -p no:xdist -m solo "$@"
