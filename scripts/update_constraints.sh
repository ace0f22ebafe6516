#!/usr/bin/env bash
# Refresh constraints.txt: install the newest versions pip offers today into a fresh
# virtual environment, run the whole test suite there (default and slow), and write
# the resolved versions to constraints.txt only if every test passed.
set -euo pipefail
if [ $# -gt 0 ]; then
  case "$1" in
    -h|--help)
      echo "usage: scripts/update_constraints.sh"
      echo
      echo "Install the newest versions pip offers into a fresh virtual environment, run the"
      echo "default and slow test suites there, and write the resolved versions to"
      echo "constraints.txt only if every test passed (takes the whole suite's time twice)."
      exit 0 ;;
    *) echo "error: unknown argument $1 (see scripts/update_constraints.sh --help)" >&2; exit 2 ;;
  esac
fi
cd "$(dirname "$0")/.."
venv="$(mktemp -d)/venv"
python3 -m venv "$venv"
"$venv/bin/python" -m pip install -q --upgrade pip
"$venv/bin/python" -m pip install -q -e ".[test]"
"$venv/bin/python" -m pytest -q
"$venv/bin/python" -m pytest -q -m slow
"$venv/bin/python" -m pip freeze --exclude-editable | grep -v '^pip==' > constraints.txt
echo "constraints.txt: $(wc -l < constraints.txt) pinned packages; review 'git diff constraints.txt'"
