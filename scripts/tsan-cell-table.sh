#!/usr/bin/env bash
# ThreadSanitizer on the cell table's lock-free insert: tests/unit/test_cell_table_race.cpp (8
# threads inserting overlapping keys) compiled alone with -fsanitize=thread against the header-only
# table (learn/cell_grid.h and core/device.h's host atomics, the code a GPU runs) and GoogleTest,
# then run; fails on any race report. Outside `make build` and `make test` (one compile, about
# 20 s): `make test-tsan`, or scripts/tsan-cell-table.sh [DIR] (the program goes to DIR, else a
# temporary folder).
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
dir=${1:-$(mktemp -d)}
mkdir -p "$dir"
${CXX:-c++} -std=c++20 -O1 -g -fsanitize=thread -fno-omit-frame-pointer -I"$root/src" \
  "$root/tests/unit/test_cell_table_race.cpp" -o "$dir/cell_table_race_tsan" \
  -lgtest -lgtest_main -pthread
TSAN_OPTIONS="halt_on_error=1 exitcode=66 ${TSAN_OPTIONS:-}" "$dir/cell_table_race_tsan"
