# Replay, scenario, launch and rviz tests.
