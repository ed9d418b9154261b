#!/usr/bin/env python3
"""Starts and stops real print hosts (Moonraker 0.11, OctoPrint 1.11) on 127.0.0.1 for tests.

Run with the python of the venv that tests/hosts/setup.sh made:

    VENV/bin/python tests/hosts/hosts.py start --dir RUNDIR --cors-origin http://127.0.0.1:PORT
        -> one JSON line on stdout:
           {"moonraker": "http://127.0.0.1:P1", "octoprint": "http://127.0.0.1:P2",
            "octoprint_key": "...", "pids": [...], ...}
    VENV/bin/python tests/hosts/hosts.py stop --dir RUNDIR

`start` writes every configuration fresh under RUNDIR (stopping whatever an earlier `start`
left there first), waits until both servers answer (and OctoPrint's virtual printer is
connected), and returns; the servers keep running in their own sessions. A watchdog process
stops them when `stop` runs, when the process that called `start` exits (or --parent-pid's
process), or after --max-minutes (15 by default), whichever comes first. `stop` ends every
process that `start` launched (found by their ids, and by a random tag in their environment so
that their children are found too) and checks that nothing listens on their ports any more.

Nothing here reaches beyond 127.0.0.1: Moonraker's announcement feed and usb.ids download,
and OctoPrint's online check, plugin blacklist, Python EOL check, software update,
plugin repository, announcements, tracking, error tracking and zeroconf discovery are off.

Only the standard library is used, except for hashing the OctoPrint password (argon2-cffi,
an OctoPrint dependency): `stop` also works with any python3.
"""

import argparse
import http.client
import json
import os
import secrets
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request

HERE = os.path.dirname(os.path.abspath(__file__))
STATE = "hosts.json"
TAG_VAR = "WEFT_HOSTS_TAG"
OCTOPRINT_USER = "weft"


# ---------------------------------------------------------------------------------------------
# processes


def proc_start_time(pid):
    """The start time of a process (clock ticks since boot), or None if it does not exist."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as f:
            data = f.read()
    except OSError:
        return None
    # the command name is in parentheses and may hold spaces: fields follow the last ')'
    fields = data[data.rindex(b")") + 2 :].split()
    if fields[0] == b"Z":  # a zombie has ended
        return None
    return int(fields[19])


def alive(pid):
    return proc_start_time(pid) is not None


def tagged_pids(tag):
    """Ids of the processes whose environment holds TAG_VAR=tag: the ones `start` launched
    and their children (environments are inherited)."""
    needle = f"{TAG_VAR}={tag}".encode()
    found = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit() or int(entry) == os.getpid():
            continue
        try:
            with open(f"/proc/{entry}/environ", "rb") as f:
                env = f.read()
        except OSError:
            continue
        if needle in env.split(b"\0"):
            found.append(int(entry))
    return found


def port_open(port):
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.settimeout(0.5)
        return s.connect_ex(("127.0.0.1", port)) == 0


def free_ports(n):
    socks = []
    try:
        for _ in range(n):
            s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
            s.bind(("127.0.0.1", 0))
            socks.append(s)
        return [s.getsockname()[1] for s in socks]
    finally:
        for s in socks:
            s.close()


def read_state(rundir):
    try:
        with open(os.path.join(rundir, STATE), encoding="utf-8") as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def write_state(rundir, state):
    path = os.path.join(rundir, STATE)
    with open(path + ".tmp", "w", encoding="utf-8") as f:
        json.dump(state, f, indent=1)
    os.replace(path + ".tmp", path)


def kill_all(state, grace=8.0):
    """Ends the servers of `state`: SIGTERM to their process groups and to every process that
    carries the tag, SIGKILL to what is left after `grace` seconds; then the watchdog. A process
    is followed by its id and start time (its environment is unreadable while it exits).
    Returns the ids that were signalled and the ids still alive at the end (empty when all
    went)."""
    tag = state["tag"]
    starts = state["starts"]
    leaders = [
        s["pid"] for s in state["servers"].values()
        if s.get("pid") and proc_start_time(s["pid"]) == starts.get(str(s["pid"]))
    ]
    targets = {}  # pid -> start time

    def living():
        return [pid for pid, t in targets.items() if proc_start_time(pid) == t]

    def send(sig):
        for pid in leaders + tagged_pids(tag):
            t = proc_start_time(pid)
            if t is not None:
                targets.setdefault(pid, t)
        for pid in leaders:
            try:
                os.killpg(pid, sig)  # each server leads its own process group (new session)
            except OSError:
                pass
        for pid in living():
            try:
                os.kill(pid, sig)
            except OSError:
                pass

    def wait(seconds):
        end = time.monotonic() + seconds
        while time.monotonic() < end and (living() or tagged_pids(tag)):
            time.sleep(0.1)

    send(signal.SIGTERM)
    wait(grace)
    if living() or tagged_pids(tag):
        send(signal.SIGKILL)
        wait(5)
    signalled = set(targets)
    wd = state.get("watchdog")
    if wd and wd != os.getpid() and proc_start_time(wd) == starts.get(str(wd)):
        try:
            os.kill(wd, signal.SIGTERM)
            signalled.add(wd)
        except OSError:
            pass
    for d in state.get("tmpdirs", []):
        shutil.rmtree(d, ignore_errors=True)
    return sorted(signalled), sorted(set(living()) | set(tagged_pids(tag)))


# ---------------------------------------------------------------------------------------------
# configuration


def moonraker_config(rundir, port, origins, exact):
    """Writes Moonraker's configuration and data folder; returns (argv tail, tmpdirs)."""
    base = os.path.join(rundir, "moonraker")
    data = os.path.join(base, "data")
    for sub in ("config", "logs", "gcodes", "misc", "comms"):
        os.makedirs(os.path.join(data, sub), exist_ok=True)
    # With misc/usb.ids present Moonraker does not download it at startup.
    with open(os.path.join(data, "misc", "usb.ids"), "w", encoding="utf-8") as f:
        f.write("# empty: no download in tests\n")
    tmpdirs = []
    sock_dir = os.path.join(data, "comms")
    if len(sock_dir) > 80:  # unix socket paths are limited to 107 bytes
        sock_dir = tempfile.mkdtemp(prefix="weft-mr-")
        tmpdirs.append(sock_dir)
    cors = list(origins)
    if not exact:
        # Moonraker accepts '*' in the port (not in the top level domain).
        cors += ["http://127.0.0.1:*", "http://localhost:*"]
    conf = os.path.join(base, "moonraker.conf")
    lines = [
        "# written by tests/hosts/hosts.py",
        "[server]",
        "host: 127.0.0.1",
        f"port: {port}",
        # no Klipper: nothing listens on this socket
        f"klippy_uds_address: {os.path.join(sock_dir, 'klippy.sock')}",
        "",
        "[authorization]",
        "trusted_clients:",
        "    127.0.0.0/8",
        "cors_domains:",
        *[f"    {o}" for o in cors],
        "",
        "[file_manager]",
        "# the gcodes folder is DATA_PATH/gcodes (-d), Moonraker 0.11 has no option for it",
        "enable_object_processing: False",
        "",
        "[announcements]",
        "enable_moonlight: False",
        "",
        "[machine]",
        "provider: none",
        "validate_service: False",
        "validate_config: False",
        "",
    ]
    with open(conf, "w", encoding="utf-8") as f:
        f.write("\n".join(lines))
    argv = [
        "-m", "moonraker",
        "-d", data,
        "-c", conf,
        "-l", os.path.join(data, "logs", "moonraker.log"),
        "-u", os.path.join(sock_dir, "moonraker.sock"),
    ]
    return argv, tmpdirs


def password_hash(password):
    try:
        from argon2 import PasswordHasher  # what OctoPrint's first password hasher writes
        return PasswordHasher().hash(password)
    except ImportError:
        from octoprint.access.users import UserManager
        return UserManager.create_password_hash(password)


def octoprint_config(rundir, port, apikey, password, fast):
    base = os.path.join(rundir, "octoprint")
    os.makedirs(os.path.join(base, "scripts", "gcode"), exist_ok=True)
    virtual = {
        "enabled": True,
        # By default the virtual printer fakes transmission errors at lines 100-115 of every
        # print (one of them a resend after a 10 s timeout): none here.
        "simulated_errors": [],
        # Its receive buffer is 64 bytes by default. A longer line (EXCLUDE_OBJECT_DEFINE ...
        # POLYGON=[[...]]) that meets a full buffer can never fit and waits for OctoPrint's
        # 10 s serial write timeout: a bigger buffer.
        "rxBuffer": 4096,
        # Tools and bed start at the ambient temperature. M109 S / M190 S only wait while the
        # heater is below the target (simulated heating is ~10 degrees a second): starting hot
        # makes a print's start G-code return at once. (M109 R / M190 R wait both ways.)
        "ambientTemperature": 280.0 if fast else 21.3,
    }
    config = {
        "api": {"allowCrossOrigin": True},
        "server": {
            "firstRun": False,
            "secretKey": secrets.token_hex(16),
            "onlineCheck": {"enabled": False},
            "pluginBlacklist": {"enabled": False},
            "pythonEolCheck": {"enabled": False},
            "seenWizards": {"corewizard": 4, "backup": 1, "classicwebcam": 1, "file_check": 1},
        },
        "serial": {"port": "VIRTUAL", "baudrate": 0, "autoconnect": True},
        "webcam": {"webcamEnabled": False},
        "plugins": {
            "_disabled": [
                "announcements", "discovery", "errortracking", "health_check",
                "pluginmanager", "softwareupdate", "tracking",
            ],
            "virtual_printer": virtual,
            "tracking": {"enabled": False},
            "classicwebcam": {"snapshot": "", "stream": ""},
        },
    }
    # JSON is YAML: OctoPrint reads this file as its config.yaml.
    with open(os.path.join(base, "config.yaml"), "w", encoding="utf-8") as f:
        json.dump(config, f, indent=1)
    users = {
        "_version": 2,
        OCTOPRINT_USER: {
            "active": True,
            "apikey": apikey,
            "groups": ["admins", "users"],
            "password": password_hash(password),
            "permissions": [],
            "roles": ["user", "admin"],
            "settings": {},
        },
    }
    with open(os.path.join(base, "users.yaml"), "w", encoding="utf-8") as f:
        json.dump(users, f, indent=1)
    if fast:
        # The virtual printer sleeps a tenth of each move's time at the feed rate times its
        # feed rate multiplier: M220 S10000 makes moves 100 times faster still.
        with open(os.path.join(base, "scripts", "gcode", "beforePrintStarted"), "w") as f:
            f.write("M220 S10000 ; tests/hosts: fast virtual printer\n")
        with open(os.path.join(base, "scripts", "gcode", "afterPrintDone"), "w") as f:
            f.write("M220 S100\n")
        with open(os.path.join(base, "scripts", "gcode", "afterPrintCancelled"), "w") as f:
            f.write("M220 S100\nM104 S0\nM140 S0\nM106 S0\nM84\n")
    return [
        "-m", "octoprint", "serve",
        "--basedir", base,
        "--host", "127.0.0.1",
        "--port", str(port),
        "--iknowwhatimdoing",  # allows running as root; no effect otherwise
    ]


# ---------------------------------------------------------------------------------------------
# start / stop


def get_json(url, headers=None, timeout=3.0):
    req = urllib.request.Request(url, headers=headers or {})
    with urllib.request.urlopen(req, timeout=timeout) as resp:
        return resp.status, json.loads(resp.read().decode() or "null")


def log_tail(path, n=30):
    try:
        with open(path, encoding="utf-8", errors="replace") as f:
            return "".join(f.readlines()[-n:])
    except OSError:
        return "(no log)"


def stop(rundir, quiet=False):
    state = read_state(rundir)
    if state is None:
        if not quiet:
            print(json.dumps({"stopped": [], "note": "nothing was started in " + rundir}))
        return 0
    signalled, left = kill_all(state)
    ports = {name: s["port"] for name, s in state["servers"].items() if s.get("port")}
    end = time.monotonic() + 5
    while True:
        still = [name for name, port in ports.items() if port_open(port)]
        if not still or time.monotonic() > end:
            break
        time.sleep(0.1)
    try:
        os.replace(os.path.join(rundir, STATE), os.path.join(rundir, STATE + ".stopped"))
    except FileNotFoundError:  # the watchdog stopped them at the same time
        pass
    if left or still:
        print(f"hosts.py stop: still alive: {left}, still listening: {still}", file=sys.stderr)
        return 1
    if not quiet:
        print(json.dumps({"stopped": signalled}))
    return 0


def start(args):
    rundir = os.path.abspath(args.dir)
    os.makedirs(rundir, exist_ok=True)
    stop(rundir, quiet=True)  # whatever an earlier start left here
    for sub in ("moonraker", "octoprint"):
        shutil.rmtree(os.path.join(rundir, sub), ignore_errors=True)

    mr_python = args.moonraker_python or os.path.join(sys.prefix, "moonraker-env", "bin", "python")
    if not os.path.exists(mr_python):
        sys.exit(f"hosts.py: no Moonraker python at {mr_python} (run tests/hosts/setup.sh VENV)")
    mr_port, op_port = free_ports(2)
    apikey = args.octoprint_key or secrets.token_hex(16).upper()
    password = secrets.token_hex(8)
    tag = secrets.token_hex(12)
    fast = not args.real_time

    mr_argv, tmpdirs = moonraker_config(rundir, mr_port, args.cors_origin, args.cors_exact)
    op_argv = octoprint_config(rundir, op_port, apikey, password, fast)

    env = {k: v for k, v in os.environ.items() if not k.startswith(("PYTHON", "MOONRAKER_"))}
    env.pop("VIRTUAL_ENV", None)
    env[TAG_VAR] = tag
    env["NO_COLOR"] = "1"

    state = {
        "tag": tag,
        "rundir": rundir,
        "servers": {},
        "starts": {},
        "tmpdirs": tmpdirs,
    }

    def spawn(argv, cwd, log_path, environ):
        """A process in a session of its own, its output in log_path, its start time kept."""
        log = open(log_path, "wb")
        p = subprocess.Popen(argv, cwd=cwd, env=environ, stdin=subprocess.DEVNULL, stdout=log,
                             stderr=subprocess.STDOUT, start_new_session=True, close_fds=True)
        log.close()
        state["starts"][str(p.pid)] = proc_start_time(p.pid)
        return p

    def launch(name, argv):
        return spawn(argv, os.path.join(rundir, name), os.path.join(rundir, name, "stdout.log"), env)

    procs = {
        "moonraker": launch("moonraker", [mr_python] + mr_argv),
        "octoprint": launch("octoprint", [sys.executable] + op_argv),
    }
    state["servers"] = {
        "moonraker": {"pid": procs["moonraker"].pid, "port": mr_port},
        "octoprint": {"pid": procs["octoprint"].pid, "port": op_port},
    }
    write_state(rundir, state)

    parent = os.getppid() if args.parent_pid is None else args.parent_pid
    deadline = time.time() + args.max_minutes * 60
    wd_env = {k: v for k, v in env.items() if k != TAG_VAR}
    wd = spawn([sys.executable, os.path.abspath(__file__), "_watchdog", "--dir", rundir,
                "--tag", tag, "--parent", str(parent),
                "--parent-start", str(proc_start_time(parent) if parent else 0),
                "--deadline", str(deadline)],
               None, os.path.join(rundir, "watchdog.log"), wd_env)
    state["watchdog"] = wd.pid
    state["deadline"] = deadline
    write_state(rundir, state)

    mr_url = f"http://127.0.0.1:{mr_port}"
    op_url = f"http://127.0.0.1:{op_port}"
    give_up = time.monotonic() + args.startup_timeout
    ready = {"moonraker": False, "octoprint": False, "virtual printer": False}
    last_err = {}
    while not all(ready.values()):
        for name, p in procs.items():
            if p.poll() is not None:
                stop(rundir, quiet=True)
                log = os.path.join(rundir, name, "stdout.log")
                sys.exit(
                    f"hosts.py: {name} exited with code {p.returncode} while starting; "
                    f"end of {log}:\n{log_tail(log)}"
                )
        if time.monotonic() > give_up:
            stop(rundir, quiet=True)
            waiting = [k for k, v in ready.items() if not v]
            sys.exit(
                f"hosts.py: gave up after {args.startup_timeout:g} s waiting for "
                f"{', '.join(waiting)} (last errors: {last_err}); logs in {rundir}/*/stdout.log"
            )
        try:
            if not ready["moonraker"]:
                status, body = get_json(mr_url + "/server/info")
                ready["moonraker"] = status == 200 and "result" in body
            if not ready["octoprint"]:
                status, _ = get_json(op_url + "/api/version", {"X-Api-Key": apikey})
                ready["octoprint"] = status == 200
            if ready["octoprint"] and not ready["virtual printer"]:
                _, body = get_json(op_url + "/api/connection", {"X-Api-Key": apikey})
                ready["virtual printer"] = body["current"]["state"] == "Operational"
        except (OSError, ValueError, KeyError, http.client.HTTPException) as e:
            last_err = {"error": str(e)}
        if not all(ready.values()):
            time.sleep(0.25)

    print(json.dumps({
        "moonraker": mr_url,
        "octoprint": op_url,
        "octoprint_key": apikey,
        "octoprint_user": OCTOPRINT_USER,
        "octoprint_password": password,
        "pids": [procs["moonraker"].pid, procs["octoprint"].pid, wd.pid],
        "moonraker_gcodes": os.path.join(rundir, "moonraker", "data", "gcodes"),
        "octoprint_uploads": os.path.join(rundir, "octoprint", "uploads"),
        "deadline": int(deadline),
    }), flush=True)
    return 0


def watchdog(args):
    """Polls twice a second; stops the servers when the state file is gone or has another tag
    (stop or a new start ran), the parent process ended, the deadline passed, or both servers
    ended by themselves."""
    rundir = args.dir
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(0))
    while True:
        state = read_state(rundir)
        if state is None or state.get("tag") != args.tag:
            return 0
        reason = None
        if time.time() > args.deadline:
            reason = "deadline"
        elif args.parent and proc_start_time(args.parent) != (args.parent_start or None):
            reason = f"parent {args.parent} ended"
        elif not any(alive(s["pid"]) for s in state["servers"].values()):
            reason = "servers ended"
        if reason:
            print(f"watchdog: {reason}: stopping the servers", flush=True)
            kill_all(state)
            try:
                os.replace(os.path.join(rundir, STATE), os.path.join(rundir, STATE + ".stopped"))
            except OSError:
                pass
            return 0
        time.sleep(0.5)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    s = sub.add_parser("start", help="start Moonraker and OctoPrint, print their URLs as JSON")
    s.add_argument("--dir", required=True, help="run directory (configs, data, logs)")
    s.add_argument("--cors-origin", action="append", default=[],
                   help="origin (scheme://host:port) allowed by Moonraker's cors_domains; "
                        "repeatable. OctoPrint allows every origin (allowCrossOrigin).")
    s.add_argument("--cors-exact", action="store_true",
                   help="no http://127.0.0.1:* and http://localhost:* in Moonraker's cors_domains")
    s.add_argument("--octoprint-key", help="API key of OctoPrint's user (default: random)")
    s.add_argument("--max-minutes", type=float, default=15.0,
                   help="the watchdog stops the servers after this long (default 15)")
    s.add_argument("--parent-pid", type=int, default=None,
                   help="the watchdog stops the servers when this process ends "
                        "(default: the caller of start; 0: never)")
    s.add_argument("--startup-timeout", type=float, default=90.0,
                   help="give up when the servers do not answer within this many seconds")
    s.add_argument("--real-time", action="store_true",
                   help="virtual printer at its own speed, heaters from 21.3 C "
                        "(default: moves 100x faster, heaters start at 280 C)")
    s.add_argument("--moonraker-python",
                   help="python of Moonraker's venv (default: sys.prefix/moonraker-env/bin/python)")
    t = sub.add_parser("stop", help="stop what start launched in --dir")
    t.add_argument("--dir", required=True)
    w = sub.add_parser("_watchdog")
    w.add_argument("--dir", required=True)
    w.add_argument("--tag", required=True)
    w.add_argument("--parent", type=int, required=True)
    w.add_argument("--parent-start", type=int, default=0)
    w.add_argument("--deadline", type=float, required=True)
    args = ap.parse_args()
    if args.cmd == "start":
        return start(args)
    if args.cmd == "stop":
        return stop(os.path.abspath(args.dir))
    return watchdog(args)


if __name__ == "__main__":
    sys.exit(main())
