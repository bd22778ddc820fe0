#!/usr/bin/env bash
# Fault drills on the node as rig.launch starts it (respawn on), with its own master on a free port:
#  1. SIGKILL: roslaunch respawns it; it answers torque again; the restart is counted
#     (~process_starts 2, /diagnostics process_restarts 1).
#  2. The master restarted under it: the node notices the new /run_id, puts its parameters on the
#     new master and exits; roslaunch respawns it; it answers torque again (~process_starts 3).
# Verdicts on what happens, not on how fast: each answer may take up to 60 s on a busy machine; the
# measured times (first input to first answer) are printed for docs/reliability.md.
# usage: check_fault_recovery.sh SOURCE_DIR WORK_DIR   (in the devel environment: env.sh)
set -euo pipefail
src=$1 work=$2
rm -rf "$work" && mkdir -p "$work"
export PATH=/usr/bin:/bin:$PATH ROS_LOG_DIR=$work/log
# The master's port: free now, and below the kernel's ephemeral range, so that no outgoing
# connection or other node's server is handed it while the master is down between the two starts
# (scripts/free_port says why).
port=$("$src/scripts/free_port")
export ROS_MASTER_URI=http://127.0.0.1:$port
pids=()
cleanup() { for p in "${pids[@]}"; do kill -INT -- "-$p" 2>/dev/null || true; done; sleep 1;
            for p in "${pids[@]}"; do kill -KILL -- "-$p" 2>/dev/null || true; done; }
trap cleanup EXIT
wait_for() {  # wait_for SECONDS DESCRIPTION COMMAND...
  local end=$((SECONDS + $1)) what=$2; shift 2
  until "$@" >/dev/null 2>&1; do
    (( SECONDS < end )) || { echo "FAIL: $what within the timeout"; tail -n 40 "$work/launch.log"; exit 1; }
    sleep 0.2
  done
}
start_master() { setsid roscore -p "$port" > "$work/master$1.log" 2>&1 & master=$!; pids+=("$master");
                 wait_for 60 "master up" rosparam get /run_id; }
starts_are() { [ "$(rosparam get /stiffness_estimator/process_starts 2>/dev/null)" = "$1" ]; }
node_pid() { rosnode info /stiffness_estimator 2>/dev/null | sed -n 's/^Pid: //p'; }
fault_at=$(date +%s.%N)
probe() {
  local r; r=$(/usr/bin/python3 "$src/test/ros/torque_probe.py" 60) || { echo "FAIL: no answer after $1: $r"; tail -n 40 "$work/launch.log"; exit 1; }
  echo "$1: $r; $(/usr/bin/python3 -c "import sys,time; print(round(time.time() - float(sys.argv[1]), 2))" "$fault_at") s from the fault to this answer"
}

start_master 1
setsid roslaunch drivetrain_stiffness rig.launch respawn_delay:=0.5 > "$work/launch.log" 2>&1 & pids+=($!)
wait_for 60 "first start" starts_are 1
probe "start"

pid=$(node_pid); [ -n "$pid" ] || { echo "FAIL: no pid for /stiffness_estimator"; exit 1; }
fault_at=$(date +%s.%N)
kill -KILL "$pid"
wait_for 60 "respawn after SIGKILL" starts_are 2
probe "respawn after SIGKILL"
diag=$(timeout 30 rostopic echo -n 3 /diagnostics | grep -A1 "key: \"process_restarts\"" | sed -n 's/ *value: "\(.*\)"/\1/p' | tail -n 1)
[ "$diag" = "1" ] || { echo "FAIL: /diagnostics process_restarts = '$diag', expected 1"; exit 1; }

old_id=$(rosparam get /run_id)
fault_at=$(date +%s.%N)
kill -INT -- "-$master"; wait "$master" 2>/dev/null || true
start_master 2
[ "$(rosparam get /run_id)" != "$old_id" ] || { echo "FAIL: the new master has the old run_id"; exit 1; }
wait_for 60 "respawn after the master restart" starts_are 3
grep -q "the ROS master restarted" "$work/launch.log" || { echo "FAIL: the node did not say why it exited"; exit 1; }
probe "respawn after master restart"
[ "$(rosparam get /stiffness_estimator/gearbox_config)" != "" ]
echo "check_fault_recovery: respawned after SIGKILL and after a master restart, restarts counted"
