"""Kill tests: SIGKILL or SIGINT at a random moment of the default run, then a rerun.

What must hold after the rerun: every case that had finished before the signal is untouched
(its summary.json and files byte for byte), every other case is computed, the manifest, the
tables and the case records agree and list every case, no temporary file is left, and no
worker outlived the killed run. Two trials run in the default suite; the full set of 20 is
marked slow: ``pytest -m slow tests/hostile/test_kill.py``.
"""

from __future__ import annotations

import json
import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import pytest

from preform.base.atomic import is_temporary_name


def _descendants(pid: int) -> set[int]:
    """Every live process below ``pid`` (from /proc; no psutil needed)."""
    children: dict[int, list[int]] = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if fields[0] != "Z":
            children.setdefault(int(fields[1]), []).append(int(entry.name))
    found: set[int] = set()
    todo = [pid]
    while todo:
        for child in children.get(todo.pop(), []):
            if child not in found:
                found.add(child)
                todo.append(child)
    return found


def _alive(pid: int) -> bool:
    try:
        return (Path("/proc") / str(pid) / "stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def _finished_cases(out: Path) -> dict[str, dict[str, bytes]]:
    """case id -> {file: bytes} of every case whose record says it finished with a result."""
    done = {}
    for summary in out.glob("*/*/summary.json"):
        rec = json.loads(summary.read_text())
        if rec["status"] in ("ok", "partial"):
            files = {"summary.json": summary.read_bytes()}
            for name in rec["files"]:
                files[name] = (summary.parent / name).read_bytes()
            done[rec["case_id"]] = files
    return done


def _check_directory(out: Path, expected_cases: int) -> None:
    manifest = json.loads((out / "manifest.json").read_text())
    cases = manifest["cases"]
    assert len(cases) == expected_cases
    records = {}
    for summary in out.glob("*/*/summary.json"):
        rec = json.loads(summary.read_text())
        records[rec["case_id"]] = rec
        assert cases[rec["case_id"]]["status"] == rec["status"]
    assert set(records) == set(cases)
    table = pd.read_csv(out / "results.csv")
    assert len(table) == expected_cases
    for scene, material, status in zip(
        table["scene"], table["material"], table["status"], strict=True
    ):
        assert records[f"{scene}/{material}"]["status"] == status
    assert not [p for p in out.rglob("*") if is_temporary_name(p.name)]


def kill_trial(tmp_path: Path, sig: signal.Signals, delay_s: float, *extra: str) -> None:
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "preform", "pipeline", "run", "--out", str(out), *extra]
    env = {k: v for k, v in os.environ.items() if k not in ("PREFORM_LIBRARY",)}
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    time.sleep(delay_s)
    below = _descendants(proc.pid)
    proc.send_signal(sig)
    try:
        proc.communicate(timeout=30)
    except subprocess.TimeoutExpired:  # pragma: no cover - the failure this test is for
        proc.kill()
        proc.communicate()
        pytest.fail(f"the run did not stop within 30 s of {sig.name}")
    # 130: preform stopped on the interrupt; 0: the run had finished; -SIGINT: the signal came
    # while the interpreter was still importing or already shutting down, outside preform's
    # code (the checks below hold either way)
    if sig == signal.SIGINT and proc.returncode not in (0, 130, -signal.SIGINT):
        pytest.fail(f"exit code {proc.returncode} after SIGINT")
    deadline = time.monotonic() + 15
    while any(_alive(p) for p in below) and time.monotonic() < deadline:
        time.sleep(0.1)
    survivors = [p for p in below if _alive(p)]
    assert not survivors, f"processes outlived the run: {survivors}"
    kept = _finished_cases(out) if out.exists() else {}
    rerun = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=600)
    assert rerun.returncode == 0, rerun.stdout + rerun.stderr
    after = _finished_cases(out)
    for case_id, files in kept.items():
        assert after[case_id] == files, f"{case_id} was redone or changed"
    n = len(json.loads((out / "manifest.json").read_text())["cases"])
    assert len(after) == n, "a case is still unfinished after the rerun"
    assert f"{len(kept)} skipped" in rerun.stdout or not kept
    _check_directory(out, n)


@pytest.mark.parametrize(
    ("sig", "delay_s"), [(signal.SIGKILL, 2.5), (signal.SIGINT, 3.5)], ids=["kill", "int"]
)
def test_kill_and_rerun_a_small_default_run(tmp_path, sig, delay_s):
    kill_trial(tmp_path, sig, delay_s, "--materials", "*-weave-*", "--workers", "2")


@pytest.mark.slow
@pytest.mark.parametrize("trial", range(20))
def test_kill_and_rerun_the_default_run_at_random_moments(tmp_path, trial):
    rng = random.Random(1000 + trial)
    sig = rng.choice([signal.SIGKILL, signal.SIGINT])
    kill_trial(tmp_path, sig, rng.uniform(0.2, 10.0))
