# Sourced by the install tests: PASS/FAIL lines and a count, so a failing run names every check
# that failed, not only the first.
failures=0
check() {  # check CONDITION MESSAGE
  if eval "$1"; then echo "PASS $2"; else echo "FAIL $2"; failures=$((failures + 1)); fi
}
finish() {
  echo "failures: $failures"
  [ "$failures" = 0 ]
}
