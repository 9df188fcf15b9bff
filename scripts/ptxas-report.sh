#!/usr/bin/env bash
# The CUDA compiler launcher of rll_device (CMakeLists.txt): ptxas-report.sh DIR COMMAND...
# Runs the compile command (which may start with another launcher, such as ccache: it replays
# ptxas's messages on a cache hit) and keeps ptxas's resource report of the object (-Xptxas=-v:
# each kernel's registers, stack frame and spills) in DIR/<object>.txt, where the budget test
# (tests/unit/test_kernel_budgets.cpp) reads it. The rest of the compiler's messages pass through;
# the report's lines (a few hundred per object) do not, so that builds stay quiet.
set -u
dir=$1
shift
out=""
prev=""
for a in "$@"; do
  [ "$prev" = "-o" ] && out=$a
  prev=$a
done
err=$(mktemp)
"$@" 2>"$err"
rc=$?
report='^ptxas info|^ +[0-9]+ bytes stack frame'
grep -v -E "$report" "$err" >&2
if [ $rc -eq 0 ] && [ -n "$out" ]; then
  mkdir -p "$dir"
  file="$dir/$(basename "$out").txt"
  grep -E "$report" "$err" >"$file.tmp"
  mv "$file.tmp" "$file"
fi
rm -f "$err"
exit $rc
