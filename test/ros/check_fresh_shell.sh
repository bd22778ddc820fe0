#!/usr/bin/env bash
# The ROS way from a fresh shell, as the README's quick start says it: in an empty environment
# (env -i, Debian's PATH only) `source DEVEL/setup.bash`, then by package name
#  1. `rosrun drivetrain_stiffness drivetrain_cli --help` runs the CLI;
#  2. `rosrun` resolves each of TOOL... to exactly one file, the expected one: DEVEL/lib/drivetrain_stiffness/TOOL
#     for the built executables, SOURCE_DIR/scripts/TOOL for the scripts (rosrun --prefix echo
#     prints the path it would run; nothing is started). rosrun skips everything below the
#     package's build/ folder, so this fails if the devel space lands there again (scripts/build);
#  3. `roslaunch --files drivetrain_stiffness NAME.launch` resolves each launch file in launch/ to
#     SOURCE_DIR/launch/NAME.launch (it only parses them: no master is started).
# Fails if setup.bash is missing or broken, or if the package or any file is not found.
# usage: check_fresh_shell.sh DEVEL_DIR SOURCE_DIR TOOL...
set -euo pipefail
devel=$1 src=$2; shift 2
err=$(mktemp)
trap 'rm -f "$err"' EXIT
fresh() {  # fresh COMMAND-STRING: runs it in bash from an empty environment after sourcing setup.bash
  # (`set --` first: a sourced script sees the caller's arguments, and catkin's setup.sh parses them)
  env -i HOME="${HOME:-/tmp}" PATH=/usr/bin:/bin bash -c 'd=$0 c=$1; set --; source "$d/setup.bash" && eval "$c"' \
    "$devel" "$1" </dev/null 2>"$err"
}
fail=0
report() {  # report WHAT OUTPUT: the failure, with what the command printed on stdout and stderr
  echo "FAIL $1"; { printf '%s\n' "$2"; cat "$err"; } | sed 's/^/     /'; fail=1
}
has_file() {  # has_file OUTPUT PATH: one line of OUTPUT names the file PATH
  local line want; want=$(realpath -e -- "$2" 2>/dev/null) || return 1
  while IFS= read -r line; do [ -n "$line" ] && [ "$(realpath -e -- "$line" 2>/dev/null)" = "$want" ] && return 0; done <<<"$1"
  return 1
}

if out=$(fresh "rosrun drivetrain_stiffness drivetrain_cli --help") && grep -q "bearing" <<<"$out"; then
  echo "ok   rosrun drivetrain_stiffness drivetrain_cli --help"
else
  report "rosrun drivetrain_stiffness drivetrain_cli --help" "$out"
fi

for tool in "$@"; do
  want=$devel/lib/drivetrain_stiffness/$tool
  [ -e "$want" ] || want=$src/scripts/$tool
  got=$(fresh "rosrun --prefix echo drivetrain_stiffness $tool") || true
  # exactly one line, that file: with two candidates rosrun asks which one and gets no answer
  if [ "$(wc -l <<<"$got")" = 1 ] && has_file "$got" "$want"; then echo "ok   rosrun drivetrain_stiffness $tool -> $got"
  else report "rosrun drivetrain_stiffness $tool: expected $want" "$got"
  fi
done

for launch in "$src"/launch/*.launch; do
  name=$(basename "$launch") args=
  [ "$name" = replay.launch ] && args="bag:=$src/test/data/torque_ripple.bag"  # its only argument without a default
  got=$(fresh "roslaunch --files drivetrain_stiffness $name $args") || true
  if has_file "$got" "$launch"; then echo "ok   roslaunch --files drivetrain_stiffness $name"
  else report "roslaunch --files drivetrain_stiffness $name: expected $launch" "$got"
  fi
done
exit $fail
