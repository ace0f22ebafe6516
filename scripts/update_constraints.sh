#!/usr/bin/env bash
# Refresh constraints.txt: install the newest versions pip offers today into a fresh
# virtual environment, run the whole test suite there (default and slow), and write
# the resolved versions to constraints.txt only if every test passed.
set -euo pipefail
cd "$(dirname "$0")/.."
venv="$(mktemp -d)/venv"
python3 -m venv "$venv"
"$venv/bin/python" -m pip install -q --upgrade pip
"$venv/bin/python" -m pip install -q -e ".[test]"
"$venv/bin/python" -m pytest -q
"$venv/bin/python" -m pytest -q -m slow
"$venv/bin/python" -m pip freeze --exclude-editable | grep -v '^pip==' > constraints.txt
echo "constraints.txt: $(wc -l < constraints.txt) pinned packages; review 'git diff constraints.txt'"
