"""Build the repository's ``Dockerfile`` without a Docker engine, then run a batch on the image.

For a machine that has no Docker engine (``make image-check``; root, network, ``debootstrap``;
about 5-10 min and 2 GB in ``--work``). Each stage's base, ``python:3.11-slim``, is stood in for by
a Debian 12 (bookworm, the base of that image) root made by ``debootstrap``, with Debian's
Python 3.11 and its headers in a virtual environment whose ``python`` and ``pip`` are first on
``PATH`` (the image's Python is built from source into ``/usr/local``; both are CPython 3.11 on the
same libc, neither has a compiler).
The Dockerfile's own instructions then run in that root, as Docker runs them: ``RUN`` through
``/bin/sh -c`` in ``chroot`` with the stage's ``ENV``, ``WORKDIR`` and ``USER``; ``COPY`` of the
build context less what ``.dockerignore`` leaves out; ``COPY --from`` between stages. Only the
instructions this Dockerfile uses are understood; any other is refused.

Then it does what the Dockerfile's header shows: ``pip show tooltransfer`` in the image, a
scheduler (the image's ``dask-scheduler``) and two workers (the image's ``CMD`` with the
scheduler's address, and its ``dask-worker``) in the image, and ``tooltransfer batch run`` of
``problems/batch/small.yaml`` from this machine's environment against them. It passes when every
row of the batch ran on the image's workers without an error and with the status and goal error
the same batch gives on this machine's process pool. What it cannot show: the engine's own
handling of layers, caches and networks, and the image's own build of Python.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import re
import shlex
import shutil
import socket
import sqlite3
import subprocess
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
BASE_IMAGE = "python:3.11-slim"
PY_ENV = "/usr/local/python"  # the stand-in Python's environment inside the root
#: Debian's packages of the stand-in: the image has Python's headers (a C extension builds once gcc
#: is in), and no compiler
BASE_PACKAGES = "python3,python3-venv,python3.11-dev,ca-certificates"
BASE_PATH = f"{PY_ENV}/bin:/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin"


@dataclass
class Stage:
    """One ``FROM`` of the Dockerfile: its root folder and the state its instructions build up."""

    name: str
    root: Path
    env: dict[str, str] = field(default_factory=lambda: {"PATH": BASE_PATH, "LANG": "C.UTF-8"})
    workdir: str = "/"
    user: str = "root"
    cmd: list[str] = field(default_factory=list)


def instructions(dockerfile: Path) -> list[tuple[int, str, str]]:
    """(line, instruction, arguments) of ``dockerfile``: comments dropped, continuations joined."""
    out: list[tuple[int, str, str]] = []
    buf, first = "", 0
    for n, raw in enumerate(dockerfile.read_text().splitlines(), 1):
        line = raw.strip()
        if not buf and (not line or line.startswith("#")):
            continue
        if buf and line.startswith("#"):
            continue
        if not buf:
            first = n
        if line.endswith("\\"):
            buf += line[:-1] + " "
            continue
        buf += line
        word, _, rest = buf.partition(" ")
        out.append((first, word.upper(), rest.strip()))
        buf = ""
    if buf:
        raise SystemExit(f"{dockerfile}:{first}: a continuation runs past the end of the file")
    return out


def ignore_rules(context: Path) -> list[re.Pattern[str]]:
    """The ``.dockerignore`` patterns of ``context`` as regular expressions on relative paths."""
    path = context / ".dockerignore"
    rules = []
    for line in path.read_text().splitlines() if path.exists() else []:
        pat = line.strip()
        if not pat or pat.startswith("#"):
            continue
        if pat.startswith("!"):
            raise SystemExit(f"{path}: exceptions ('{pat}') are not understood here")
        rx = re.escape(pat.strip("/")).replace(r"\*\*/", "(?:.*/)?").replace(r"\*\*", ".*")
        rx = rx.replace(r"\*", "[^/]*").replace(r"\?", "[^/]")
        rules.append(re.compile(rx + "$"))
    return rules


def copy_context(context: Path, dest: Path) -> int:
    """Copy the build context into ``dest`` less what ``.dockerignore`` leaves out; the files copied."""
    rules = ignore_rules(context)
    count = 0
    for dirpath, dirnames, filenames in os.walk(context):
        rel_dir = Path(dirpath).relative_to(context)
        keep = []
        for d in sorted(dirnames):
            rel = (rel_dir / d).as_posix()
            if not any(r.match(rel) for r in rules):
                keep.append(d)
        dirnames[:] = keep
        for f in filenames:
            rel = (rel_dir / f).as_posix()
            if any(r.match(rel) for r in rules):
                continue
            target = dest / rel
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(Path(dirpath) / f, target, follow_symlinks=False)
            count += 1
    return count


def make_base(work: Path, mirror: str, ca_bundle: Path | None) -> Path:
    """The stand-in for ``python:3.11-slim`` (module docstring), made once in ``work/base``;
    ``ca_bundle``: certificate authorities pip is to trust (a network behind an intercepting proxy,
    as a Docker engine there would need them too), written to the root's ``/etc/pip.conf``."""
    base = work / "base"
    if not (base / "usr" / "include" / "python3.11" / "Python.h").exists():  # not yet, or interrupted
        shutil.rmtree(base, ignore_errors=True)
        subprocess.run(["debootstrap", "--variant=minbase", f"--include={BASE_PACKAGES}", "bookworm", str(base),
                        mirror], check=True)
    shutil.copy2("/etc/resolv.conf", base / "etc" / "resolv.conf")
    if ca_bundle is not None:
        shutil.copy2(ca_bundle, base / "etc" / "ssl" / "certs" / "site-ca.crt")
        (base / "etc" / "pip.conf").write_text("[global]\ncert = /etc/ssl/certs/site-ca.crt\n")
    if (base / PY_ENV.lstrip("/") / "bin" / "pip").exists():
        return base
    with mounted(base):
        chroot(base, ["/bin/sh", "-c", f"python3 -m venv {PY_ENV} && {PY_ENV}/bin/pip install -q --upgrade pip"],
               {"PATH": BASE_PATH})
    return base


@contextlib.contextmanager
def mounted(root: Path) -> Iterator[None]:
    """``/proc`` and ``/dev`` of the machine mounted in ``root`` while inside."""
    done = []
    try:
        for src, dst, opts in (("proc", "proc", ["-t", "proc"]), ("/dev", "dev", ["--rbind"])):
            target = root / dst
            target.mkdir(exist_ok=True)
            subprocess.run(["mount", *opts, src, str(target)], check=True)
            done.append(target)
        yield
    finally:
        for target in reversed(done):
            subprocess.run(["umount", "--recursive", "--lazy", str(target)], check=False)


def chroot(root: Path, argv: list[str], env: dict[str, str], *, user: str = "root", cwd: str = "/",
           background: bool = False, log: Path | None = None) -> subprocess.Popen[bytes] | None:
    """Run ``argv`` in ``root`` as ``user`` in ``cwd`` with exactly ``env``."""
    uid, gid, home = account(root, user)
    env = {"HOME": home, **env}
    cmd = ["chroot", f"--userspec={uid}:{gid}", str(root),
           "/usr/bin/env", "-i", *(f"{k}={v}" for k, v in env.items()),
           "/bin/sh", "-c", f"cd {shlex.quote(cwd)} && exec " + shlex.join(argv)]
    if background:
        out = open(log, "wb") if log else subprocess.DEVNULL  # the process keeps the file open
        return subprocess.Popen(cmd, stdout=out, stderr=subprocess.STDOUT)
    subprocess.run(cmd, check=True)
    return None


def account(root: Path, user: str) -> tuple[str, str, str]:
    """(uid, gid, home) of ``user`` (a name or uid) in the root's own ``/etc/passwd``."""
    for line in (root / "etc" / "passwd").read_text().splitlines():
        parts = line.split(":")
        if user in (parts[0], parts[2]):
            return parts[2], parts[3], parts[5]
    raise SystemExit(f"no user {user!r} in the image")


def build(dockerfile: Path, context: Path, work: Path, mirror: str, ca_bundle: Path | None) -> Stage:
    """Run the Dockerfile's instructions (module docstring); the last stage."""
    base = make_base(work, mirror, ca_bundle)
    stages: dict[str, Stage] = {}
    stage: Stage | None = None
    for n, word, args in instructions(dockerfile):
        where = f"{dockerfile.name}:{n}"
        print(f"[{where}] {word} {args[:100]}", flush=True)
        if word == "FROM":
            parts = args.split()
            if parts[0] != BASE_IMAGE:
                raise SystemExit(f"{where}: only FROM {BASE_IMAGE} has a stand-in here, not {parts[0]}")
            name = parts[2] if len(parts) == 3 and parts[1].upper() == "AS" else f"stage{len(stages)}"
            root = work / f"stage-{name}"
            shutil.rmtree(root, ignore_errors=True)
            subprocess.run(["cp", "-a", str(base), str(root)], check=True)
            stage = stages[name] = Stage(name, root)
            continue
        if stage is None:
            raise SystemExit(f"{where}: {word} before FROM")
        if word == "RUN":
            with mounted(stage.root):
                chroot(stage.root, ["/bin/sh", "-c", args], stage.env, user=stage.user, cwd=stage.workdir)
        elif word == "WORKDIR":
            stage.workdir = args if args.startswith("/") else f"{stage.workdir.rstrip('/')}/{args}"
            (stage.root / stage.workdir.lstrip("/")).mkdir(parents=True, exist_ok=True)
        elif word == "COPY":
            parts = shlex.split(args)
            src_stage = None
            if parts[0].startswith("--from="):
                src_stage = stages[parts.pop(0).split("=", 1)[1]]
            if len(parts) != 2 or parts[0].startswith("--"):
                raise SystemExit(f"{where}: COPY [--from=STAGE] SRC DEST is understood, not {args!r}")
            src, dest = parts
            dest_path = stage.root / (dest if dest.startswith("/") else f"{stage.workdir}/{dest}").lstrip("/")
            if src_stage is None:
                if src != ".":
                    raise SystemExit(f"{where}: COPY from the context is understood for '.', not {src!r}")
                print(f"    {copy_context(context, dest_path)} files of the build context", flush=True)
            else:
                shutil.copytree(src_stage.root / src.lstrip("/"), dest_path, dirs_exist_ok=True, symlinks=True)
        elif word == "ENV":
            for item in shlex.split(args):
                key, sep, value = item.partition("=")
                if not sep:
                    raise SystemExit(f"{where}: ENV KEY=VALUE is understood, not {item!r}")
                stage.env[key] = value
        elif word == "USER":
            stage.user = args
        elif word == "EXPOSE":
            pass  # documentation for the engine: the stand-in shares the machine's network
        elif word == "CMD":
            stage.cmd = json.loads(args)
        else:
            raise SystemExit(f"{where}: {word} is not understood here")
    if stage is None:
        raise SystemExit(f"{dockerfile}: no FROM")
    return stage


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def wait_for(port: int, seconds: float) -> None:
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        with socket.socket() as s:
            if s.connect_ex(("127.0.0.1", port)) == 0:
                return
        time.sleep(0.5)
    raise SystemExit(f"nothing answered on port {port} in {seconds:.0f} s")


def run_batch(image: Stage, work: Path) -> None:
    """The Dockerfile header's recipe on one machine: scheduler and worker in the image, the batch here."""
    print("[run] pip show tooltransfer", flush=True)
    batch_run = [str(Path(sys.executable).with_name("tooltransfer")), "batch", "run",
                 str(ROOT / "problems" / "batch" / "small.yaml")]
    port = free_port()
    addr = f"tcp://127.0.0.1:{port}"
    procs: list[subprocess.Popen[bytes]] = []
    with mounted(image.root):
        chroot(image.root, ["pip", "show", "tooltransfer"], image.env, user=image.user, cwd=image.workdir)
        try:
            # the scheduler and a second worker through the image's wrappers (dask's Kubernetes operator
            # starts its pods with those names)
            for argv, log in ((["dask-scheduler", "--port", str(port), "--dashboard-address", ":0"], "scheduler"),
                              ([*image.cmd, addr, "--nthreads", "2", "--dashboard-address", ":0"], "worker"),
                              (["dask-worker", addr, "--nthreads", "1", "--dashboard-address", ":0"], "worker2")):
                print(f"[run] in the image: {shlex.join(argv)}", flush=True)
                p = chroot(image.root, argv, image.env, user=image.user, cwd=image.workdir, background=True,
                           log=work / f"{log}.log")
                assert p is not None
                procs.append(p)
                if log == "scheduler":
                    wait_for(port, 60)
            from distributed import Client

            with Client(addr, timeout=60) as client:
                client.wait_for_workers(2, timeout=120)
                print(f"[run] {len(client.scheduler_info()['workers'])} workers in the image", flush=True)
            db = work / "small.sqlite"
            db.unlink(missing_ok=True)
            cmd = [*batch_run, "--db", str(db), "--scheduler", addr]
            print(f"[run] here: {shlex.join(cmd)}", flush=True)
            subprocess.run(cmd, check=True, env={**os.environ, "OPENBLAS_NUM_THREADS": "1"})
        finally:
            for p in procs:
                p.terminate()
            for p in procs:
                try:
                    p.wait(timeout=20)
                except subprocess.TimeoutExpired:
                    p.kill()
    local = work / "small-local.sqlite"
    local.unlink(missing_ok=True)
    print("[run] here, the same batch on the local process pool, to compare", flush=True)
    subprocess.run([*batch_run, "--db", str(local), "--workers", "2", "-q"], check=True,
                   env={**os.environ, "OPENBLAS_NUM_THREADS": "1"})
    image_rows, local_rows = rows_of(db), rows_of(local)
    statuses = sorted({row[0] for row in image_rows.values()})
    # the scheduler's only worker is the image's: `batch run` refuses a cluster without one
    print(f"[run] {len(image_rows)} rows from the image's worker, statuses {statuses}", flush=True)
    if not image_rows or "error" in statuses:
        raise SystemExit(f"the batch did not run cleanly on the image's worker (logs in {work})")
    differ = [k for k in local_rows if image_rows.get(k) != local_rows[k]]
    print(f"[run] the same status and goal error [m] as on this machine in {len(local_rows) - len(differ)} of "
          f"{len(local_rows)} rows", flush=True)
    if differ or image_rows.keys() != local_rows.keys():
        raise SystemExit(f"the image plans otherwise than this machine: {differ[:5]}")


def rows_of(db: Path) -> dict[tuple[str, str], tuple[str, float | None]]:
    """(task, variant) -> (status, goal error rounded to 1e-9 m) of a results file."""
    with contextlib.closing(sqlite3.connect(db)) as con:
        rows = con.execute("SELECT task_id, variant, status, goal_error FROM results").fetchall()
    return {(t, v): (s, None if g is None else round(g, 9)) for t, v, s, g in rows}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--work", type=Path, default=Path("/var/tmp/tooltransfer-image"),
                    help="folder for the roots (the base is kept for the next run) and the logs")
    ap.add_argument("--mirror", default="http://deb.debian.org/debian", help="Debian mirror for debootstrap")
    ap.add_argument("--dockerfile", type=Path, default=ROOT / "Dockerfile")
    ap.add_argument("--context", type=Path, default=ROOT)
    ap.add_argument("--ca-bundle", type=Path, default=os.environ.get("PIP_CERT") or None,
                    help="certificate authorities for pip in the roots (default: $PIP_CERT, if set)")
    ap.add_argument("--keep", action="store_true", help="keep the stages' roots (removed after a pass)")
    args = ap.parse_args()
    if os.geteuid() != 0 or shutil.which("debootstrap") is None:
        raise SystemExit("needs root and debootstrap (apt-get install debootstrap)")
    args.work.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    image = build(args.dockerfile.resolve(), args.context.resolve(), args.work.resolve(), args.mirror,
                  args.ca_bundle)
    print(f"[build] done in {time.perf_counter() - t0:.0f} s: {image.root}", flush=True)
    run_batch(image, args.work.resolve())
    if not args.keep:
        for root in args.work.resolve().glob("stage-*"):
            shutil.rmtree(root)
    print(f"[ok] the Dockerfile built and its worker ran the batch ({time.perf_counter() - t0:.0f} s in all)")


if __name__ == "__main__":
    main()
