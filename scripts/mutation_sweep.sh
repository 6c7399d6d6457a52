#!/bin/bash
# mutation_sweep.sh — do the tests fail when the code is wrong? Each mutant
# of scripts/mutants.txt (one deliberate fault: a sign, a bound, a unit) is
# applied to a fresh clone of this checkout, built, and run against the
# tests its block names (ctest -R), then, if none failed, against the whole
# default suite (ctest -LE slow). A mutant is
#   KILLED     some test failed (the tests see the fault),
#   SURVIVED   every test passed (a fault the tests let through: a test to
#              write, or a mutant that changes nothing a user could see),
#   STILLBORN  it did not build.
# The clone (of the checkout's last commit) keeps the checkout untouched
# and its build apart; it has ../shared beside it when this checkout does
# (test_events_ref).
#
# Usage: scripts/mutation_sweep.sh [ID ...]   (default: every mutant)
#   WORK=dir to keep the clone (default: a temporary folder, removed)
#   JOBS=n  for make and ctest (default 2)
# One line per mutant on stdout; progress and the logs' places on stderr.
# Takes minutes per survivor (the whole suite runs for it): not part of
# the test suite. docs/testing.md has the last sweep's table.
set -u
top=$(cd "$(dirname "$0")/.." && pwd)
list=$top/scripts/mutants.txt
jobs=${JOBS:-2}
work=${WORK:-$(mktemp -d /tmp/elfm_mutants.XXXXXX)}
keep=${WORK:+1}
cleanup() { [ -z "$keep" ] && rm -rf "$work"; }
trap cleanup EXIT

# the mutants: blocks of "id:", "file:", "tests:", "old:", "new:" lines
ids=()
declare -A f_of t_of o_of n_of seen
id=""
while IFS= read -r line; do
  case "$line" in
  "id: "*) id=${line#id: }; ids+=("$id")
    # an id given twice: the later block would stand for both (a second
    # csv_pol hid the first for a session)
    if [ -n "${seen[$id]:-}" ]; then echo "mutation_sweep: id '$id' twice in $list" >&2; exit 2; fi
    seen[$id]=1 ;;
  "file: "*) f_of[$id]=${line#file: } ;;
  "tests: "*) t_of[$id]=${line#tests: } ;;
  "old: "*) o_of[$id]=${line#old: } ;;
  "new: "*) n_of[$id]=${line#new: } ;;
  esac
done < "$list"
[ $# -gt 0 ] && ids=("$@")

# the checkout's last commit (uncommitted changes are not in the sweep);
# a clone kept from an earlier run (WORK=) is moved to it
src=$work/src
if [ ! -d "$src/.git" ]; then
  git clone -q "$top" "$src" || exit 1
else
  (cd "$src" && git fetch -q "$top" HEAD && git checkout -q . && git reset -q --hard FETCH_HEAD) || exit 1
fi
[ -d "$top/../shared" ] && [ ! -e "$work/shared" ] && ln -s "$(cd "$top/../shared" && pwd)" "$work/shared"
mkdir -p "$src/build" "$work/logs"
echo "mutation_sweep: building $src (logs in $work/logs)" >&2
(cd "$src/build" && cmake .. -DCMAKE_BUILD_TYPE=Release > "$work/logs/cmake.txt" 2>&1 &&
  make -j"$jobs" > "$work/logs/build.txt" 2>&1) || { echo "mutation_sweep: the clean build failed" >&2; exit 1; }

failed_tests() { grep -E '\*\*\*(Failed|Timeout|Exception)' "$1" | awk '{print $4}' | tr '\n' ' '; }

for id in "${ids[@]}"; do
  file=${f_of[$id]:-}
  if [ -z "$file" ]; then echo "$id UNKNOWN"; continue; fi
  echo "mutation_sweep: $id ($file)" >&2
  # the old text must stand exactly once; perl takes both texts literally
  if ! (cd "$src" && OLD=${o_of[$id]} NEW=${n_of[$id]} perl -0pi -e \
        'my $n = () = /\Q$ENV{OLD}\E/g; die "found $n times\n" if $n != 1; s/\Q$ENV{OLD}\E/$ENV{NEW}/' "$file"); then
    echo "$id NOT-APPLIED"; continue
  fi
  log=$work/logs/$id
  if ! (cd "$src/build" && make -j"$jobs" > "$log.build.txt" 2>&1); then
    echo "$id STILLBORN"
  else
    (cd "$src/build" && ctest -LE slow -R "${t_of[$id]}" -j"$jobs" --timeout 600 > "$log.tests.txt" 2>&1)
    bad=$(failed_tests "$log.tests.txt")
    if [ -n "$bad" ]; then
      echo "$id KILLED by $bad"
    else
      (cd "$src/build" && ctest -LE slow -j"$jobs" --timeout 600 > "$log.all.txt" 2>&1)
      bad=$(failed_tests "$log.all.txt")
      if [ -n "$bad" ]; then echo "$id KILLED by $bad(whole suite)"
      else echo "$id SURVIVED"; fi
    fi
  fi
  (cd "$src" && git checkout -q -- "$file")
done
