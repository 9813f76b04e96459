#!/usr/bin/env bash
# The README's two commands:
#   ./run.sh demo [args]   set up, then run the main job (the headless chase demo)
#   ./run.sh test [args]   set up, then run the whole test suite (args go to pytest)
#   ./run.sh grade PATH [args]  set up, then grade a submission (see docs/teaching.md, "Grading a submission")
set -euo pipefail
TOP=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
cd "$TOP"

job=${1:-}
case "$job" in
  demo|test|grade) shift ;;
  *) echo "usage: ./run.sh demo|test|grade [args]" >&2; exit 2 ;;
esac

./setup.sh
# catkin's setup scripts read unset variables, so nounset is off while sourcing; and they
# read the sourcing script's arguments as their own (--help among them), so those wait aside.
args=("$@")
set --
set +u
# shellcheck disable=SC1091
source env.sh
set -u
set -- "${args[@]}"

case "$job" in
  demo) exec rosrun chase_tools chase_demo "$@" ;;
  # One worker per CPU; --dist loadscope keeps a module's tests (and its shared
  # launches and builds) on one worker, so each runs once.
  test) exec python -m pytest -n auto --dist loadscope "$@" ;;
  grade) exec grade "$@" ;;
esac
