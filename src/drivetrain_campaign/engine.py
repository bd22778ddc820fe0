"""Where the tasks run: in-process (--serial), an embedded dask LocalCluster on the loopback (the
default), or a lab's dask scheduler (--scheduler, optionally over TLS). docs/campaign.md.

A worker lost mid-task (killed, its machine gone) is the scheduler's business: the nanny or the
other workers take its tasks again, so every bag still ends with exactly one result. Tasks are
pure functions of their job dict; their results are small dicts (the rows).
"""

import contextlib
import faulthandler
import os
import sys
import tempfile
import threading

import dask

# The task functions travel by value (cloudpickle), so workers on other machines need this
# package's Python modules no more than its source tree: only drivetrain_replay at the same path.
_BY_VALUE = False
WORKER_WAIT_S = 60.0  # [s] for the first worker of a --scheduler
START_TIMEOUT_S = 180.0  # [s] for the cluster and the client to come up
LOOPBACK_HTTP = "127.0.0.1:0"  # the embedded cluster's HTTP servers: loopback, any free port


def _start_timed_out(what):
    print(f"drivetrain_campaign: {what} did not start in {START_TIMEOUT_S:g} s; thread stacks follow", file=sys.stderr)
    faulthandler.dump_traceback(all_threads=True)
    sys.stderr.flush()
    os._exit(1)


def _register_by_value():
    global _BY_VALUE
    if _BY_VALUE:
        return
    import cloudpickle

    from . import inputs, replay_task
    for module in (inputs, replay_task, sys.modules[__name__]):
        cloudpickle.register_pickle_by_value(module)
    _BY_VALUE = True


def check_worker(paths, programs, directories):
    """Runs on each worker before the campaign: what it cannot read, run or write."""
    problems = [f"cannot read '{p}'" for p in paths if not os.access(p, os.R_OK)]
    problems += [f"cannot run '{p}'" for p in programs if not os.access(p, os.X_OK)]
    problems += [f"cannot write into '{d}'" for d in directories if not os.access(d, os.W_OK | os.X_OK)]
    return problems


class SerialEngine:
    """Runs every task here, one after the other (the reference a cluster run must equal)."""

    name = "serial"
    workers = 1

    def map_unordered(self, function, jobs):
        for job in jobs:
            try:
                result = function(job)
            except Exception as e:  # as on a cluster: the task's failure is its row's, not the campaign's
                yield job, None, f"{type(e).__name__}: {e}"
                continue
            yield job, result, None

    def preflight(self, paths, programs, directories):
        return {"local": check_worker(paths, programs, directories)}

    def close(self):
        pass


class DaskEngine:
    """dask.distributed: an embedded LocalCluster on 127.0.0.1 (workers > 0) or the scheduler at
    `address`. security: a distributed.Security or None."""

    def __init__(self, workers=None, address=None, security=None):
        from distributed import Client, LocalCluster

        _register_by_value()
        self._stack = contextlib.ExitStack()
        # dask has no start-up timeout for a LocalCluster: a cluster that has not come up in
        # START_TIMEOUT_S ends the campaign with the Python stacks of every thread (why), not a hang.
        watchdog = threading.Timer(START_TIMEOUT_S, _start_timed_out, args=(address or "local cluster",))
        watchdog.daemon = True
        watchdog.start()
        self._stack.callback(watchdog.cancel)
        if address:
            self.name = address
            self.client = self._stack.enter_context(Client(address, security=security, timeout="20s"))
            try:  # a scheduler whose workers have not joined yet (or never will): say so
                self.client.wait_for_workers(1, timeout=WORKER_WAIT_S)
            except TimeoutError as e:
                self.close()
                raise ValueError(f"--scheduler {address}: no worker joined in {WORKER_WAIT_S:g} s") from e
        else:
            n = workers or os.cpu_count() or 1
            self.name = f"local cluster, {n} worker process{'es' if n > 1 else ''}"
            # One single-threaded worker process per core: each task is one replay process.
            # The loopback only: a dask scheduler runs any code a client sends it. The workers'
            # scratch space is this campaign's own, not the machine-wide /tmp/dask-worker-space
            # whose lock files every dask process on the machine shares and purges.
            space = self._stack.enter_context(tempfile.TemporaryDirectory(prefix="drivetrain_campaign_"))
            # The workers' statistical profiler (a stack sample every 10 ms) slowed the replay running
            # beside it by 15 %: a 60 s load_sweep bag took 6.8-7.4 s in a worker, 5.8-6.0 s with the
            # profiler off, 5.9-6.3 s alone. Nobody reads the profile here (no dashboard). The nanny
            # hands this configuration to the worker processes it starts.
            # dask 2022.12 starts an HTTP server in the scheduler and in every worker whatever the
            # dashboard options say (Node.start_http_server runs unconditionally), bound to every
            # interface unless given an address: with dashboard_address=None the scheduler's is on
            # 0.0.0.0:8787 and [::]:8787 and shows the network its logs, call stacks and every
            # worker's address and directory; each worker's, /health and /metrics. They cannot be
            # turned off, so they get no routes (the campaign reads no page of theirs, and the
            # loopback is every local user's) and are bound to the loopback (LocalCluster, below).
            self._stack.enter_context(dask.config.set({"distributed.worker.profile.enabled": False,
                                                       "distributed.worker.profile.interval": "1000ms",
                                                       "distributed.scheduler.http.routes": [],
                                                       "distributed.worker.http.routes": []}))
            # The HTTP servers on a port of the kernel's choosing: two campaigns on one machine never
            # contend for 8787. The scheduler's address goes through scheduler_kwargs so that it
            # stays a plain HTTP server (LocalCluster's dashboard_address would also ask for the
            # bokeh dashboard); worker_dashboard_address asks for the workers' too, which without
            # bokeh (Debian has none) is a debug log line.
            cluster = self._stack.enter_context(LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                                             host="127.0.0.1", dashboard_address=None,
                                                             scheduler_kwargs={"dashboard_address": LOOPBACK_HTTP},
                                                             worker_dashboard_address=LOOPBACK_HTTP,
                                                             silence_logs=40, local_directory=space))
            self.client = self._stack.enter_context(Client(cluster))
        self.workers = len(self.client.scheduler_info()["workers"])
        watchdog.cancel()

    def worker_pids(self):
        return self.client.run(os.getpid)

    def preflight(self, paths, programs, directories):
        return self.client.run(check_worker, list(paths), list(programs), list(directories))

    def map_unordered(self, function, jobs):
        """Yields (job, result, error) as tasks finish; a task that raised gives its error."""
        from distributed import as_completed

        jobs = list(jobs)
        if not jobs:
            return
        # pure=False: a task is a run, not a cached value (the campaign has its own cache).
        futures = {self.client.submit(function, job, pure=False): job for job in jobs}
        for future in as_completed(futures):
            job = futures[future]
            try:
                yield job, future.result(), None
            except Exception as e:  # the task's own failure: its row says so, the campaign goes on
                yield job, None, f"{type(e).__name__}: {e}"
            finally:
                future.release()

    def close(self):
        self._stack.close()


def security_from(ca_file, cert, key):
    """dask's Security for a TLS scheduler (all three files), or None."""
    given = [x for x in (ca_file, cert, key) if x]
    if not given:
        return None
    if len(given) != 3:
        raise ValueError("--tls-ca-file, --tls-cert and --tls-key: give all three or none")
    for option, path in (("--tls-ca-file", ca_file), ("--tls-cert", cert), ("--tls-key", key)):
        if not os.access(path, os.R_OK):
            raise ValueError(f"{option}: cannot read '{path}'")
    from distributed.security import Security

    return Security(tls_ca_file=ca_file, tls_client_cert=cert, tls_client_key=key, require_encryption=True)
