#!/usr/bin/env bash
# Installs everything pixelkit needs on a fresh Debian machine; safe to re-run.
#  - ngspice, its shared library and headers, and chromium (the report test renders
#    the HTML report headless) from Debian's packages (apt-get)
#  - pixelkit and its Python dependencies (pip, editable install); the open
#    GF180MCU model files ship inside the package (pixelkit/tech/models/)
set -euo pipefail
cd "$(dirname "$0")"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
missing=()
for pkg in ngspice libngspice0 libngspice0-dev chromium; do
  dpkg -s "$pkg" >/dev/null 2>&1 || missing+=("$pkg")
done
if [ "${#missing[@]}" -gt 0 ]; then
  echo "setup: installing ${missing[*]} (apt-get)" >&2
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}" >/dev/null
fi
PY="${PYTHON:-python3}"
"$PY" -m pip install -q --disable-pip-version-check --root-user-action=ignore -e '.[test]'
echo "setup: done ($(ngspice --version 2>/dev/null | grep -o 'ngspice-[0-9]*' | head -1))" >&2
