#!/usr/bin/env bash
# One style: clang-format (.clang-format) over the C and C++ sources and flake8 (.flake8) over the
# Python, both from Debian. Part of the test command (scripts/run_tests.sh). To fix: run
# `clang-format -i` on the files it names; flake8 names each line to change.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_packages.sh clang-format flake8
mapfile -t cpp < <(git ls-files -- '*.cpp' '*.h' '*.c')
clang-format --dry-run --Werror "${cpp[@]}"
mapfile -t py < <(git ls-files -- '*.py')
flake8 "${py[@]}"
echo "style: ${#cpp[@]} C/C++ and ${#py[@]} Python files as .clang-format and .flake8 say"
