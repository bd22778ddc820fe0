"""drivetrain_campaign: a rig test campaign (many bags) replayed, calibrated and trended.

Every bag runs through `drivetrain_replay --report --calibrate`, exactly as it would alone; the
bags run as tasks on dask.distributed (an embedded cluster on the loopback, or a lab's scheduler);
a CUSUM over each bag's calibrated estimates raises the alarm (docs/campaign.md).
"""

# Part of every cache key: a change to what a row holds or how it is computed bumps it.
VERSION = "2"
