#!/usr/bin/python3
"""drivetrain_campaign end to end on short simulated bags (docs/campaign.md; issue: test campaigns):
a local cluster on the loopback gives the serial run's table byte for byte; a worker killed
mid-campaign leaves every bag with exactly one row, equal to the serial one; a second run
replays nothing, a grown campaign replays only the new bag; a truncated bag and a file that is
not a bag get their rows with reasons; the change detector raises on a 10 % loss of mesh
stiffness and stays quiet on a constant campaign; a bag with accelerometers gives the identified
modes' columns, one without leaves them empty; every socket the campaign's processes listen on is
on 127.0.0.1, and the embedded cluster's HTTP servers serve no page.

Environment: DRIVETRAIN_RIG_SIM, DRIVETRAIN_REPLAY and DRIVETRAIN_CLI (the built programs;
CMakeLists.txt sets them).
"""

import csv
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
CAMPAIGN = os.path.join(ROOT, "scripts", "drivetrain_campaign")
CONFIG = os.path.join(ROOT, "config", "gearboxes", "seed_servo.yaml")
RIG_SIM = os.environ.get("DRIVETRAIN_RIG_SIM", "drivetrain_rig_sim")
REPLAY = os.environ.get("DRIVETRAIN_REPLAY", "drivetrain_replay")
CLI = os.environ.get("DRIVETRAIN_CLI", "drivetrain_cli")
# Short load sweeps: every hold scaled down, still whole gear turns at 600 rpm (load_sweep.hpp).
SIM = ["--scenario", "load_sweep", "--config", CONFIG, "--duration", "6", "--speed-rpm", "600"]


def sim_campaign(directory, bags, **step):
    cmd = [RIG_SIM, *SIM, "--campaign", directory, "--bags", str(bags), "--interval", "3600"]
    for option, value in step.items():
        cmd += ["--" + option.replace("_", "-"), str(value)]
    subprocess.run(cmd, check=True, capture_output=True)


def campaign(out, bags, *options, check=True):
    proc = subprocess.run([CAMPAIGN, *bags, "--config", CONFIG, "--out", out, "--replay", REPLAY, "--no-plots", *options],
                          capture_output=True, text=True, timeout=900)
    if check and proc.returncode != 0:
        raise AssertionError(f"drivetrain_campaign exit {proc.returncode}:\n{proc.stderr}")
    return proc


def rows(out):
    with open(os.path.join(out, "campaign.csv"), newline="") as f:
        return list(csv.DictReader(f))


def table_bytes(out):
    with open(os.path.join(out, "campaign.csv"), "rb") as f:
        return f.read()


def run_info(out):
    import json

    with open(os.path.join(out, "run.json")) as f:
        return json.load(f)


def processed(out):
    return run_info(out)["processed"]


def children(pid):
    """Direct children of pid, from /proc."""
    found = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/stat") as f:
                    fields = f.read().rsplit(")", 1)[1].split()
                if int(fields[1]) == pid:
                    found.append(int(entry))
            except OSError:
                pass
    return found


def command(pid):
    try:
        with open(f"/proc/{pid}/cmdline", "rb") as f:
            return f.read().replace(b"\0", b" ").decode(errors="replace")
    except OSError:
        return ""


def descendants(pid):
    """pid and every process below it, from /proc."""
    parents = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/stat") as f:
                    parents[int(entry)] = int(f.read().rsplit(")", 1)[1].split()[1])
            except OSError:  # gone meanwhile
                pass
    tree = {pid}
    grown = True
    while grown:
        below = {child for child, parent in parents.items() if parent in tree} - tree
        tree |= below
        grown = bool(below)
    return tree


def socket_address(field):
    """/proc/net/{tcp,udp}[6]'s HOST:PORT (hex, the host in 32-bit words of the kernel's byte
    order) as '127.0.0.1:8786' or '[::]:8787'."""
    host, port = field.split(":")
    raw = b"".join(bytes.fromhex(host[i:i + 8])[::-1] for i in range(0, len(host), 8))
    if len(raw) == 4:
        return f"{socket.inet_ntop(socket.AF_INET, raw)}:{int(port, 16)}"
    return f"[{socket.inet_ntop(socket.AF_INET6, raw)}]:{int(port, 16)}"


def listening_sockets(pids):
    """{(pid, 'tcp'|'tcp6'|'udp'|'udp6', address)}: the sockets these processes hold open that
    anyone may connect or send to, from /proc alone (no ss or lsof on a bare CI machine): TCP
    sockets in LISTEN, UDP sockets not connected to a peer."""
    found = set()
    for pid in pids:
        try:
            inodes = set()
            for fd in os.listdir(f"/proc/{pid}/fd"):
                try:
                    target = os.readlink(f"/proc/{pid}/fd/{fd}")
                except OSError:  # closed meanwhile
                    continue
                if target.startswith("socket:["):
                    inodes.add(target[len("socket:["):-1])
            for proto in ("tcp", "tcp6", "udp", "udp6"):
                with open(f"/proc/{pid}/net/{proto}") as f:  # the process's own network namespace
                    next(f)
                    for line in f:
                        fields = line.split()
                        state, inode = fields[3], fields[9]
                        # 0A: TCP_LISTEN; 07 (TCP_CLOSE) on a UDP socket: bound, no peer
                        if inode in inodes and state == ("0A" if proto.startswith("tcp") else "07"):
                            found.add((pid, proto, socket_address(fields[1])))
        except OSError:  # the process ended meanwhile
            pass
    return found


class Campaign(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="campaign_test_")
        cls.step = os.path.join(cls.tmp, "step")        # 10 % loss of mesh stiffness from bag 3 on
        cls.constant = os.path.join(cls.tmp, "constant")
        sim_campaign(cls.step, 6, step_at=3, step_mesh_scale=0.9)
        sim_campaign(cls.constant, 4, epoch=1767225600 + 30 * 86400, seed=101)
        cls.damaged = os.path.join(cls.tmp, "damaged")
        os.makedirs(cls.damaged)
        with open(os.path.join(cls.step, "bag_001.bag"), "rb") as f:
            data = f.read()
        with open(os.path.join(cls.damaged, "truncated.bag"), "wb") as f:
            f.write(data[: len(data) // 2])   # a recording cut off halfway
        with open(os.path.join(cls.damaged, "notes.bag"), "w") as f:
            f.write("not a bag\n")
        shutil.copy(os.path.join(cls.step, "bag_000.bag"), os.path.join(cls.damaged, "copy_of_000.bag"))
        cls.inputs = [cls.step, os.path.join(cls.damaged, "*.bag")]
        cls.serial = os.path.join(cls.tmp, "serial")
        campaign(cls.serial, cls.inputs, "--serial")

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def test_rows_damaged_bags_and_duplicates(self):
        r = {os.path.basename(x["bag"]): x for x in rows(self.serial)}
        # 6 campaign bags + truncated + notes; the copy of bag_000 is reported once, on bag_000's row.
        self.assertEqual(sorted(r), sorted([f"bag_00{i}.bag" for i in range(6)] + ["truncated.bag", "notes.bag"]))
        self.assertTrue(r["truncated.bag"]["status"].startswith("incomplete: "), r["truncated.bag"]["status"])
        self.assertIn("messages read before it", r["truncated.bag"]["status"])
        self.assertTrue(r["notes.bag"]["status"].startswith("refused: "), r["notes.bag"]["status"])
        self.assertIn("#ROSBAG", r["notes.bag"]["status"])  # the replay's reason: not a bag
        self.assertTrue(r["bag_000.bag"]["duplicates"].endswith("copy_of_000.bag"))
        for i in range(6):
            row = r[f"bag_00{i}.bag"]
            self.assertEqual(row["status"], "ok")
            self.assertEqual(float(row["start"]), 1767225600 + 3600 * i)  # the campaign's stamps, sorted
            self.assertGreater(int(row["accepted"]), 0)
            self.assertGreater(int(row["calibration_updates"]), 0)
            self.assertEqual(len(row["sha256"]), 64)
        # sorted by first stamp (the truncated copy of bag_001 starts with it), the refused one last
        table = rows(self.serial)
        starts = [float(x["start"]) for x in table[:-1]]
        self.assertEqual(starts, sorted(starts))
        self.assertEqual(os.path.basename(table[-1]["bag"]), "notes.bag")
        order = [os.path.basename(x["bag"]) for x in table if x["bag"].startswith(self.step)]
        self.assertEqual(order, [f"bag_00{i}.bag" for i in range(6)])

    def test_bag_reports_keep_what_they_need_unless_all_is_asked(self):
        # Default (--bag-outputs report): the summary, the calibrated gearbox and the small CSV files,
        # none of the per-reading or per-sample ones; --bag-outputs all: every topic, the same row.
        r = {os.path.basename(x["bag"]): x for x in rows(self.serial)}
        report = os.path.join(self.serial, r["bag_000.bag"]["report"])
        self.assertEqual(sorted(os.listdir(os.path.join(report, "csv"))),
                         ["calibration.csv", "mesh_period_stats.csv", "resonance.csv", "te_spectrum.csv"])
        self.assertTrue(os.path.exists(os.path.join(report, "calibrated_gearbox.yaml")))
        out = os.path.join(self.tmp, "all_outputs")
        bag = os.path.join(self.step, "bag_000.bag")
        campaign(out, [bag], "--serial", "--bag-outputs", "all")
        full = rows(out)[0]
        self.assertIn("measured_te.csv", os.listdir(os.path.join(out, full["report"], "csv")))
        self.assertIn("stiffness.csv", os.listdir(os.path.join(out, full["report"], "csv")))
        for column, value in full.items():
            if column not in ("alarm", "alarm_reason", "out_of_family", "family_reason", "duplicates"):
                self.assertEqual(value, r["bag_000.bag"][column], column)  # a one-bag campaign has no reference
        # One report directory per bag serves every option: after a run with the default, a cached
        # row of an earlier `all` run must not be taken for a report that no longer holds its topics.
        campaign(out, [bag], "--serial")
        self.assertEqual(processed(out), 1)
        campaign(out, [bag], "--serial", "--bag-outputs", "all")
        self.assertEqual(processed(out), 1)
        self.assertIn("measured_te.csv", os.listdir(os.path.join(out, full["report"], "csv")))
        # With plots (these tests run without): outputs.bag also gets what plot_replay.py reads, the
        # CSV files stay the report's; the replay refuses a report whose plots would miss a topic.
        sys.path.insert(0, os.path.join(ROOT, "src"))
        from drivetrain_campaign.replay_task import replay_command
        job = {"replay": REPLAY, "bag": bag, "config": CONFIG, "plots": True, "bag_outputs": "report"}
        cmd = replay_command(job, "/nonexistent")
        bag_topics = cmd[cmd.index("--topics") + 1].split(",")
        csv_topics = cmd[cmd.index("--csv-topics") + 1].split(",")
        for plotted in ("transmission_error", "stiffness", "resonance", "mesh_period_stats"):
            self.assertIn(plotted, bag_topics)
        self.assertEqual(sorted(csv_topics), ["calibration", "mesh_period_stats", "resonance", "te_spectrum"])
        self.assertNotIn("--no-plots", cmd)

    def test_change_detector_raises_on_a_ten_percent_loss(self):
        r = {os.path.basename(x["bag"]): x for x in rows(self.serial)}
        with open(os.path.join(self.step, "truth.csv"), newline="") as f:
            truth = {x["bag"]: float(x["mesh_stiffness_scale"]) for x in csv.DictReader(f)}
        for i in range(6):
            row = r[f"bag_00{i}.bag"]
            # the calibration finds each bag's true mesh scale (docs/calibration.md: within 5 %)
            self.assertAlmostEqual(float(row["mesh_stiffness_scale"]), truth[f"bag_00{i}.bag"], delta=0.05)
            self.assertEqual(row["alarm"], "true" if i >= 3 else "false", (i, row["alarm_reason"]))
        self.assertIn("mesh_stiffness_scale -", r["bag_003.bag"]["alarm_reason"])

    def test_identified_modes_from_the_accelerometers(self):
        # The model's modes at the gearbox's torque, by dominant coordinate (drivetrain_cli modes, the
        # mean mesh stiffness as the replay's model uses): the identified frequencies lie within 1 %.
        import yaml

        with open(CONFIG) as f:
            torque = yaml.safe_load(f)["dynamics"]["torque"]
        cli = json.loads(subprocess.run([CLI, "modes", "--config", CONFIG, "--torque", str(torque)], check=True,
                                        capture_output=True, text=True).stdout)
        model = {m["dominant_coordinate"]: m["natural_frequency_hz"] for m in cli["modes"]["mesh_mean"]}
        self.assertEqual(sorted(model), ["x", "x_g", "x_p"])
        bags = os.path.join(self.tmp, "vibration")
        os.makedirs(bags)
        with_vibration, without = os.path.join(bags, "ripple.bag"), os.path.join(bags, "quiet.bag")
        for bag, rate in ((with_vibration, "51200"), (without, "0")):
            subprocess.run([RIG_SIM, "--scenario", "torque_ripple", "--duration", "10", "--config", CONFIG,
                            "--vibration-rate", rate, "--out", bag], check=True, capture_output=True)
        out = os.path.join(self.tmp, "vibration_campaign")
        campaign(out, [bags], "--serial", "--bag-outputs", "all")
        r = {os.path.basename(x["bag"]): x for x in rows(out)}
        row = r["ripple.bag"]
        csv_dir = os.path.join(out, row["report"], "csv")
        with open(os.path.join(csv_dir, "modal_identification.csv"), newline="") as f:
            identified = list(csv.DictReader(f))
        # One record per 4 s of 51.2 kHz samples, each a message and its rows in the CSV file.
        self.assertEqual(int(row["modal_identifications"]), len({x["stamp"] for x in identified}))
        self.assertEqual(int(row["modal_identifications"]), 2)
        for name, frequency in model.items():
            last = [x for x in identified if x["status"] == "identified" and x["dominant"] == name]
            if frequency > 51200 / 2:  # above Nyquist: no record can hold it
                self.assertEqual(last, [], name)
                self.assertEqual(row[f"modal_frequency_{name}"], "", name)
                self.assertEqual(row[f"modal_frequency_{name}_std"], "", name)
                continue
            self.assertTrue(last, name)
            self.assertEqual(float(row[f"modal_frequency_{name}"]), float(last[-1]["frequency"]), name)
            self.assertEqual(float(row[f"modal_frequency_{name}_std"]), float(last[-1]["frequency_std"]), name)
            self.assertAlmostEqual(float(row[f"modal_frequency_{name}"]) / frequency, 1.0, delta=0.01, msg=name)
            self.assertGreater(float(row[f"modal_frequency_{name}_std"]), 0.0, name)
        with open(os.path.join(csv_dir, "calibration.csv"), newline="") as f:
            final = list(csv.DictReader(f))[-1]
        for column in ("modal_updates", "modal_gated"):
            self.assertEqual(int(row[column]), int(float(final[column])), column)
        self.assertGreater(int(row["modal_updates"]), 0)  # the identified frequencies update the calibration
        quiet = r["quiet.bag"]
        self.assertEqual(quiet["status"], "ok")
        self.assertEqual((quiet["modal_identifications"], quiet["modal_updates"], quiet["modal_gated"]), ("0", "0", "0"))
        for name in model:
            self.assertEqual((quiet[f"modal_frequency_{name}"], quiet[f"modal_frequency_{name}_std"]), ("", ""), name)
        # The load sweeps' accelerometers (one record each) give the bearing modes too.
        for x in rows(self.serial):
            if x["bag"].startswith(self.step):
                self.assertEqual(int(x["modal_identifications"]), 1, x["bag"])
                for name in ("x_p", "x_g"):
                    self.assertAlmostEqual(float(x[f"modal_frequency_{name}"]) / model[name], 1.0, delta=0.01,
                                           msg=(x["bag"], name))

    def test_cluster_equals_serial_and_a_rerun_replays_nothing(self):
        out = os.path.join(self.tmp, "cluster")
        campaign(out, self.inputs, "--workers", "2")
        self.assertEqual(table_bytes(out), table_bytes(self.serial))
        self.assertEqual(processed(out), 8)  # 6 + truncated + notes: the copy is not replayed
        campaign(out, self.inputs, "--workers", "2")
        self.assertEqual(processed(out), 0)
        self.assertEqual(run_info(out)["hashed"], 0)  # unchanged files: not even read again
        self.assertEqual(table_bytes(out), table_bytes(self.serial))
        grown = self.inputs + [os.path.join(self.constant, "bag_000.bag")]
        campaign(out, grown, "--workers", "2")
        self.assertEqual(processed(out), 1)
        self.assertEqual(run_info(out)["hashed"], 1)
        self.assertEqual(len(rows(out)), 9)

    def test_every_socket_of_a_two_worker_campaign_listens_on_the_loopback_only(self):
        # A dask scheduler runs whatever a client sends it, and its HTTP servers tell the cluster's
        # addresses, directories and logs: nothing of the embedded cluster may be reachable from
        # the network. The campaign's process tree is sampled while it runs (the scheduler and
        # the nannies live in the campaign's process, each worker in a process of its own).
        out = os.path.join(self.tmp, "loopback")
        proc = subprocess.Popen([CAMPAIGN, os.path.join(self.constant, "bag_000.bag"), "--config", CONFIG, "--out", out,
                                 "--replay", REPLAY, "--no-plots", "--workers", "2"],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        seen, names = set(), {}
        deadline = time.monotonic() + 300
        while proc.poll() is None and time.monotonic() < deadline:
            found = listening_sockets(descendants(proc.pid))
            names.update({pid: command(pid)[:70] for pid, _, _ in found if pid not in names})
            seen |= found
            time.sleep(0.1)
        _, stderr = proc.communicate(timeout=600)
        self.assertEqual(proc.returncode, 0, stderr)
        listed = "\n".join(f"{pid} {proto} {address}  {names[pid]}" for pid, proto, address in sorted(seen))
        # Seen while the cluster was up: the scheduler in the campaign's process, and both workers.
        self.assertIn(proc.pid, {pid for pid, _, _ in seen}, listed)
        self.assertGreaterEqual(len({pid for pid, _, _ in seen} - {proc.pid}), 2, listed)
        beyond = sorted(x for x in seen if not x[2].startswith("127.0.0.1:"))
        self.assertEqual(beyond, [], "listening beyond the loopback:\n" + listed)

    def test_a_killed_worker_leaves_every_bag_with_one_row(self):
        reference = os.path.join(self.tmp, "constant_serial")
        campaign(reference, [self.constant], "--serial")
        self.assertFalse(any(r["alarm"] == "true" for r in rows(reference)))  # a constant campaign: quiet
        out = os.path.join(self.tmp, "killed")
        proc = subprocess.Popen([CAMPAIGN, self.constant, "--config", CONFIG, "--out", out, "--replay", REPLAY,
                                 "--no-plots", "--workers", "2"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        killed = None
        deadline = time.monotonic() + 300
        while killed is None and proc.poll() is None and time.monotonic() < deadline:
            for worker in children(proc.pid):
                if any("drivetrain_replay" in command(c) for c in children(worker)):
                    os.kill(worker, signal.SIGKILL)  # mid-bag: its replay is running
                    killed = worker
                    break
            time.sleep(0.05)
        _, stderr = proc.communicate(timeout=600)
        self.assertIsNotNone(killed, "no worker was caught running a replay")
        self.assertEqual(proc.returncode, 0, stderr)
        got = rows(out)
        self.assertEqual(sorted(r["bag"] for r in got), sorted(r["bag"] for r in rows(reference)))
        self.assertEqual(table_bytes(out), table_bytes(reference))
        self.assertEqual(os.listdir(os.path.join(out, "bags")).__len__(), 4)  # no scratch left behind


class EmbeddedCluster(unittest.TestCase):
    """The engine's LocalCluster itself, in this process (no bags, no replay)."""

    def test_its_http_servers_serve_nothing(self):
        # dask starts an HTTP server in the scheduler and in each worker that cannot be turned off;
        # bound to the loopback, they are still every local user's: they must serve no page (the
        # scheduler's logs, call stacks, workers' addresses and directories; /health, /metrics).
        import http.client
        import json

        sys.path.insert(0, os.path.join(ROOT, "src"))
        from drivetrain_campaign.engine import DaskEngine
        engine = DaskEngine(workers=1)
        self.addCleanup(engine.close)
        info = engine.client.scheduler_info()
        servers = {"scheduler": info["services"]["dashboard"]}
        servers.update({worker: w["services"]["dashboard"] for worker, w in info["workers"].items()})
        self.assertEqual(len(servers), 2)

        def get(port, path):  # http.client, not urllib: no proxy from the environment, the loopback only
            connection = http.client.HTTPConnection("127.0.0.1", port, timeout=20)
            try:
                connection.request("GET", path)
                response = connection.getresponse()
                return response.status, response.read()
            finally:
                connection.close()

        for who, port in servers.items():
            for path in ("/json/identity.json", "/info/main/logs.html", "/info/main/workers.html", "/health", "/metrics"):
                self.assertEqual(get(port, path)[0], 404, (who, path))
            # tornado's routing table as the server lists it: nothing but the list itself
            status, body = get(port, "/sitemap.json")
            self.assertEqual((status, json.loads(body)["paths"]), (200, ["/sitemap.json"]), who)


def stop(proc):
    """SIGTERM first: dask-worker's nanny then closes its worker process too."""
    proc.terminate()
    try:
        proc.wait(timeout=15)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()


def free_port():
    """A port for a dask-scheduler: scripts/free_port's (free now, below the kernel's ephemeral
    range, where the worker's and the client's own outgoing connections cannot be handed it)."""
    return int(subprocess.run([os.path.join(ROOT, "scripts", "free_port")], check=True, capture_output=True,
                              text=True).stdout)


def make_tls(directory):
    """A CA and one certificate it signs for 127.0.0.1 (scheduler, worker and client alike)."""
    def ssl(*args):
        subprocess.run(["openssl", *args], check=True, capture_output=True, cwd=directory)

    ssl("req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "2", "-subj", "/CN=campaign test CA",
        "-keyout", "ca.key", "-out", "ca.pem")
    ssl("req", "-newkey", "rsa:2048", "-nodes", "-subj", "/CN=127.0.0.1", "-keyout", "node.key", "-out", "node.csr")
    with open(os.path.join(directory, "san.cnf"), "w") as f:
        f.write("subjectAltName=IP:127.0.0.1\n")
    ssl("x509", "-req", "-in", "node.csr", "-CA", "ca.pem", "-CAkey", "ca.key", "-CAcreateserial", "-days", "2",
        "-extfile", "san.cnf", "-out", "node.pem")
    return [os.path.join(directory, f) for f in ("ca.pem", "node.pem", "node.key")]


class LabScheduler(unittest.TestCase):
    """--scheduler: an existing dask-scheduler and dask-worker (as on a lab's machines), over TLS."""

    def test_campaign_on_a_tls_scheduler_equals_serial_and_plain_tcp_is_refused(self):
        tmp = tempfile.mkdtemp(prefix="campaign_tls_")
        self.addCleanup(shutil.rmtree, tmp, True)
        bags = os.path.join(tmp, "bags")
        sim_campaign(bags, 2, seed=7)
        ca, cert, key = make_tls(tmp)
        tls = ["--tls-ca-file", ca, "--tls-cert", cert, "--tls-key", key]
        port = free_port()
        procs = [subprocess.Popen(["dask-scheduler", "--host", "127.0.0.1", "--port", str(port), "--protocol", "tls",
                                   "--no-dashboard", "--dashboard-address", "127.0.0.1:0", *tls], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
        self.addCleanup(lambda: [stop(p) for p in reversed(procs)])
        address = f"tls://127.0.0.1:{port}"
        procs.append(subprocess.Popen(["dask-worker", address, "--nworkers", "1", "--nthreads", "1", "--no-dashboard", "--dashboard-address", "127.0.0.1:0",
                                       "--host", "127.0.0.1", *tls], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        serial = os.path.join(tmp, "serial")
        campaign(serial, [bags], "--serial")
        out = os.path.join(tmp, "lab")
        campaign(out, [bags], "--scheduler", address, *tls)
        self.assertEqual(table_bytes(out), table_bytes(serial))
        # without the certificates the client cannot talk to the scheduler: refused, with the reason
        refused = campaign(os.path.join(tmp, "plain"), [bags], "--scheduler", f"tcp://127.0.0.1:{port}", check=False)
        self.assertEqual(refused.returncode, 1, refused.stderr)
        self.assertIn("drivetrain_campaign:", refused.stderr)

    @unittest.skipUnless(os.geteuid() == 0, "needs root to start a worker as another user")
    def test_a_worker_that_cannot_read_the_bags_stops_the_campaign_before_it_starts(self):
        # A lab worker without the shared storage: here a worker running as `nobody`, which cannot
        # enter the 0700 directory that holds the bags (the client, root, can).
        tmp = tempfile.mkdtemp(prefix="campaign_preflight_")
        self.addCleanup(shutil.rmtree, tmp, True)
        bags = os.path.join(tmp, "bags")
        sim_campaign(bags, 1)
        space = tempfile.mkdtemp(prefix="campaign_nobody_")
        os.chmod(space, 0o777)
        self.addCleanup(shutil.rmtree, space, True)
        port = free_port()
        address = f"tcp://127.0.0.1:{port}"
        procs = [subprocess.Popen(["dask-scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard", "--dashboard-address", "127.0.0.1:0"],
                                  stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
        self.addCleanup(lambda: [stop(p) for p in reversed(procs)])
        procs.append(subprocess.Popen(["setpriv", "--reuid=65534", "--regid=65534", "--clear-groups", "dask-worker", address,
                                       "--nworkers", "1", "--nthreads", "1", "--no-dashboard", "--dashboard-address", "127.0.0.1:0", "--host", "127.0.0.1",
                                       "--local-directory", space], env={"PATH": "/usr/bin:/bin", "HOME": space},
                                      # in its own directory: `nobody` may not enter the checkout's
                                      # (a clone under a 0700 mktemp directory), and a worker that
                                      # cannot read its working directory never joins
                                      cwd=space, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        refused = campaign(os.path.join(tmp, "out"), [bags], "--scheduler", address, check=False)
        self.assertEqual(refused.returncode, 1, refused.stderr)
        self.assertRegex(refused.stderr, r"worker tcp://127\.0\.0\.1:\d+: cannot read '" + bags + "/bag_000.bag'")
        self.assertNotIn("drivetrain_campaign: 1 bags", refused.stderr)  # nothing was replayed


if __name__ == "__main__":
    unittest.main(verbosity=2)
