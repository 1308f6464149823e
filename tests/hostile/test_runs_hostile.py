"""A run a user can leave going and believe afterwards: issue 10, items 1-6 and 11.

Each test drives a real run (in process, or the real CLI in a subprocess) into a hostile
situation and asserts what must hold: the located message or recorded status, no traceback,
nothing written outside --out, nothing lost that had finished.
"""

from __future__ import annotations

import errno
import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import pytest

from preform.base.atomic import atomic_open, is_temporary_name
from preform.library import load_library
from preform.pipeline.rundir import LOCK_NAME, RunDirectory
from preform.pipeline.runner import folder_name, input_hash, make_cases, run_cases
from preform.pipeline.scene import load_scene
from preform.plugin_manager import PluginHost


def fabric(name: str, fate: str = "ok", work_s: float = 0.0) -> str:
    """One library entry of the runtoy architecture (tests/hostile/conftest.py), YAML flow."""
    return (
        f"- {{name: {name!r}, architecture: runtoy, source: test, note: test fabric, "
        f"fate: {fate}, work_s: {work_s}}}\n"
    )


# -- helpers ---------------------------------------------------------------------------------


@pytest.fixture
def host(runenv, monkeypatch: pytest.MonkeyPatch) -> PluginHost:
    for key in ("PYTHONPATH", "PREFORM_LOAD_PLUGINS", "RUNTOY_PIDS"):
        monkeypatch.setenv(key, runenv.env[key])
    h = PluginHost()
    h.discover()
    assert "runtoy" in h.registry.names("architectures")
    return h


def run_in_process(runenv, host: PluginHost, library: Path, scene: Path, **kwargs):
    lib = load_library([library], bundled=False, env=False, registry=host.registry)
    loaded = load_scene(scene, host.registry)
    timeout_s = kwargs.pop("timeout_s", None)
    cases = make_cases(lib, [loaded], runenv.out, host, timeout_s=timeout_s)
    return run_cases(cases, runenv.out, host, **{"engine": "serial", **kwargs})


def manifest(out: Path) -> dict:
    return json.loads((out / "manifest.json").read_text())


def statuses(out: Path) -> dict[str, str]:
    return {k: v["status"] for k, v in manifest(out)["cases"].items()}


def table(out: Path) -> pd.DataFrame:
    return pd.read_csv(out / "results.csv", keep_default_na=False)


def assert_consistent(out: Path) -> None:
    """Manifest, tables and every case's summary.json say the same, about every case folder."""
    cases = manifest(out)["cases"]
    summaries = {}
    for path in out.glob("*/*/summary.json"):
        rec = json.loads(path.read_text())
        summaries[rec["case_id"]] = rec
        assert cases[rec["case_id"]]["case_dir"] == str(path.parent.relative_to(out))
    assert set(summaries) == set(cases)
    for case_id, rec in summaries.items():
        assert cases[case_id]["status"] == rec["status"]
    rows = table(out)
    assert sorted(f"{s}/{m}" for s, m in zip(rows["scene"], rows["material"], strict=True)) == (
        sorted(cases)
    )
    for s, m, st in zip(rows["scene"], rows["material"], rows["status"], strict=True):
        assert cases[f"{s}/{m}"]["status"] == st
    assert not [p for p in out.rglob("*") if is_temporary_name(p.name)]


def no_traceback(proc: subprocess.CompletedProcess[str]) -> None:
    assert "Traceback" not in proc.stderr and "Traceback" not in proc.stdout, proc.stderr


# -- 3. safe, unique case folders ---------------------------------------------------------

HOSTILE_NAMES = [
    "..",
    ".",
    "../escape",
    "../../etc/passwd",
    "/absolute/path",
    "a/b",
    "a\\b",
    ".hidden",
    "CON",
    "nul.txt",
    "a b",
    "a_b",
    "a  b",
    "ünïcödé",
    "x" * 300,
    "-dash",
    "trailing.",
    "tab\tname",
    "*",
    "~",
]


@pytest.mark.parametrize("name", HOSTILE_NAMES)
def test_folder_name_is_one_safe_component_inside_out(name, tmp_path):
    folder = folder_name(name)
    assert re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9._-]*", folder), folder
    assert len(folder) <= 80 and not folder.endswith(".")
    assert (tmp_path / folder).resolve().parent == tmp_path.resolve()


def test_folder_names_are_unique_and_stable():
    folders = [folder_name(n) for n in HOSTILE_NAMES]
    assert len(set(folders)) == len(HOSTILE_NAMES)
    assert folders == [folder_name(n) for n in HOSTILE_NAMES]  # no state, no seed
    assert folder_name("plain-weave-600") == "plain-weave-600"  # plain names stay readable


def test_scene_named_dotdot_and_colliding_fabrics_stay_inside_out(runenv, host):
    lib = runenv.library(fabric("a b"), fabric("a_b"), fabric("a/b"))
    scene = runenv.scene(name="..")
    before = sorted(p.name for p in runenv.root.iterdir())
    report = run_in_process(runenv, host, lib, scene)
    assert [r.status for r in report.results] == ["ok", "ok", "ok"]
    assert sorted(p.name for p in runenv.root.iterdir()) == sorted({*before, "out"})
    dirs = {c["case_dir"] for c in manifest(runenv.out)["cases"].values()}
    assert len(dirs) == 3
    for d in dirs:
        assert (runenv.out / d).resolve().is_relative_to(runenv.out.resolve())
        assert (runenv.out / d / "work.txt").is_file()
    assert_consistent(runenv.out)


@pytest.mark.parametrize("where", ["file", "below a file"])
def test_out_that_is_a_file_is_a_clear_error(runenv, where):
    target = runenv.root / "results.txt"
    target.write_text("the user's notes\n")
    out = target if where == "file" else target / "sub"
    cmd = runenv.command(runenv.library(fabric("a")), runenv.scene())
    cmd[cmd.index("--out") + 1] = str(out)
    proc = subprocess.run(cmd, env=runenv.env, capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2, proc.stderr
    no_traceback(proc)
    assert str(target) in proc.stderr and "nothing was run" in proc.stderr
    assert target.read_text() == "the user's notes\n"


# -- 1. a deterministic resume cache --------------------------------------------------------


def test_rerun_with_another_hash_seed_skips(runenv):
    lib = runenv.library(fabric("a"), fabric("b", fate="partial"))
    scene = runenv.scene(outputs="[work_txt, work]")
    first = runenv.run(lib, scene, "--engine", "serial")
    assert first.returncode == 0, first.stderr
    for seed in ("1", "2"):
        env = {**runenv.env, "PYTHONHASHSEED": seed}
        proc = subprocess.run(
            runenv.command(lib, scene, "--engine", "serial"),
            env=env,
            capture_output=True,
            text=True,
            timeout=60,
        )
        assert "2 case(s)" in proc.stdout and "2 skipped" in proc.stdout, proc.stdout


def test_bundled_scene_rerun_with_another_hash_seed_skips(tmp_path):
    out = tmp_path / "o"
    cmd = [sys.executable, "-m", "preform", "pipeline", "run", "--scene", "unit-cell"]
    cmd += ["--materials", "plain-weave-150", "--out", str(out), "--engine", "serial"]
    for seed, expected in (("1", "1 ok"), ("2", "1 skipped")):
        env = {**os.environ, "PYTHONHASHSEED": seed}
        proc = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=120)
        assert expected in proc.stdout, proc.stdout + proc.stderr


def _hash_of(host, runenv, fabric_text, scene_text, scene_name="s.yaml"):
    lib_path = runenv.library(fabric_text)
    scene_path = runenv.root / scene_name
    scene_path.write_text(scene_text)
    lib = load_library([lib_path], bundled=False, env=False, registry=host.registry)
    scene, data = load_scene(scene_path, host.registry)
    fab = next(iter(lib))
    return input_hash(fab.model_dump(mode="json", exclude_none=True), scene, data, host)


def test_hash_ignores_key_order(runenv, host):
    a = _hash_of(
        host,
        runenv,
        "- {name: a, architecture: runtoy, source: s, note: n, work_s: 0.5, fate: ok}\n",
        "name: s\noutputs: [work_txt]\ndescription: d\n",
    )
    b = _hash_of(
        host,
        runenv,
        "- {fate: ok, work_s: 0.5, note: n, source: s, architecture: runtoy, name: a}\n",
        "description: d\noutputs: [work_txt]\nname: s\n",
    )
    assert a == b


def test_hash_follows_mesh_content_not_its_path(runenv, host):
    mesh = runenv.root / "tool.stl"
    scene = "name: s\noutputs: [work_txt]\ndescription: tool.stl\n"
    mesh.write_text("solid a\nendsolid a\n")
    first = _hash_of(host, runenv, fabric("a"), scene)
    assert _hash_of(host, runenv, fabric("a"), scene) == first
    mesh.write_text("solid b\nendsolid b\n")
    assert _hash_of(host, runenv, fabric("a"), scene) != first


def test_hash_follows_the_step_version_not_unrelated_plugins(runenv, host, monkeypatch):
    scene = "name: s\noutputs: [work_txt]\n"
    base = _hash_of(host, runenv, fabric("a"), scene)

    class Unrelated:
        pass

    host.add(Unrelated(), "unrelated", version="9.9")
    assert _hash_of(host, runenv, fabric("a"), scene) == base
    monkeypatch.setenv("RUNTOY_STEP_VERSION", "2")
    other = PluginHost()
    other.discover()
    assert _hash_of(other, runenv, fabric("a"), scene) != base


# -- 2. runs add to the directory; a second concurrent run is refused -----------------------


def test_runs_with_other_scenes_and_materials_merge(runenv, host):
    lib = runenv.library(fabric("a"), fabric("b"), fabric("c", fate="raise"))
    s1, s2 = runenv.scene(name="first"), runenv.scene(name="second", outputs="[work]")
    run_in_process(runenv, host, lib, s1)
    run_in_process(runenv, host, lib, s2)
    assert statuses(runenv.out) == {
        "first/a": "ok",
        "first/b": "ok",
        "first/c": "failed",
        "second/a": "ok",
        "second/b": "ok",
        "second/c": "failed",
    }
    assert len(table(runenv.out)) == 6
    assert len(manifest(runenv.out)["runs"]) == 2
    assert_consistent(runenv.out)


def test_runs_with_other_materials_merge_through_the_cli(runenv):
    lib = runenv.library(fabric("a"), fabric("b"))
    scene = runenv.scene()
    assert runenv.run(lib, scene, "--engine", "serial", "--materials", "a").returncode == 0
    assert runenv.run(lib, scene, "--engine", "serial", "--materials", "b").returncode == 0
    assert statuses(runenv.out) == {"work-scene/a": "ok", "work-scene/b": "ok"}
    assert list(table(runenv.out)["material"]) == ["a", "b"]
    assert_consistent(runenv.out)


def test_a_second_run_into_a_held_directory_is_refused(runenv):
    lib, scene = runenv.library(fabric("a")), runenv.scene()
    with RunDirectory(runenv.out):
        proc = runenv.run(lib, scene, "--engine", "serial")
    assert proc.returncode == 2
    no_traceback(proc)
    assert "another preform run is writing into" in proc.stderr
    assert f"pid {os.getpid()}" in proc.stderr
    assert not (runenv.out / "work-scene").exists()
    assert runenv.run(lib, scene, "--engine", "serial").returncode == 0  # released


def test_two_concurrent_runs_one_refused_one_complete(runenv):
    lib = runenv.library(*(fabric(f"f{i}", work_s=1.5) for i in range(4)))
    scene = runenv.scene()
    first = runenv.start(lib, scene, "--engine", "serial")
    deadline = time.monotonic() + 30
    while not (runenv.out / "manifest.json").exists() and time.monotonic() < deadline:
        time.sleep(0.05)
    second = runenv.run(lib, scene, "--engine", "serial")
    _, err = first.communicate(timeout=120)
    assert first.returncode == 0, err
    assert second.returncode == 2 and "another preform run" in second.stderr
    assert set(statuses(runenv.out).values()) == {"ok"}
    assert_consistent(runenv.out)


# -- 4. temporary files: exactly preform's --------------------------------------------------


def test_killed_writer_leaves_a_temporary_that_the_next_run_removes(runenv, host):
    victim = runenv.out / "work-scene" / "a" / "half.json"
    code = (
        "import os, sys\n"
        "from preform.base.atomic import atomic_open\n"
        f"with atomic_open({str(victim)!r}) as f:\n"
        "    f.write('{\"half\": ')\n"
        "    f.flush()\n"
        "    os._exit(9)\n"
    )
    subprocess.run([sys.executable, "-c", code], check=False, timeout=60)
    left = [p for p in victim.parent.iterdir() if is_temporary_name(p.name)]
    assert len(left) == 1 and not victim.exists()
    run_in_process(runenv, host, runenv.library(fabric("a")), runenv.scene())
    assert not [p for p in runenv.out.rglob("*") if is_temporary_name(p.name)]


USER_FILES = [
    ".draft.tmp.txt",
    ".notes.tmp",
    ".summary.json.tmp",
    ".a.b.preform-tmp.txt",
    "x.preform-tmp",
    ".results.csv.ABCDEFGH.preform-tmp.csv",  # capitals: never made by mkstemp
    "summary.json.bak",
]


@pytest.mark.parametrize("name", USER_FILES)
def test_users_files_that_look_temporary_are_kept(runenv, host, name):
    user = runenv.out / "work-scene" / name
    user.parent.mkdir(parents=True)
    user.write_text("mine")
    run_in_process(runenv, host, runenv.library(fabric("a")), runenv.scene())
    assert user.read_text() == "mine"


def test_temporary_names_are_recognised():
    made = []
    target = Path(os.environ.get("TMPDIR", "/tmp")) / f"preform-probe-{os.getpid()}.json"
    from preform.base.atomic import atomic_path

    with atomic_path(target) as tmp:
        made.append(tmp.name)
        tmp.write_text("{}")
    target.unlink()
    assert is_temporary_name(made[0]) and made[0].endswith(".json")


# -- 5. a dead or hanging case costs only itself -----------------------------------------------


@pytest.mark.parametrize(
    ("fate", "words"),
    [
        ("exit", "died (exit code 7)"),
        ("segv", "died (killed by SIGSEGV)"),
        ("kill", "died (killed by SIGKILL (out of memory?"),
    ],
)
def test_dead_worker_fails_only_its_case(runenv, host, fate, words):
    lib = runenv.library(
        *(fabric(f"ok{i}", work_s=0.2) for i in range(3)), fabric("victim", fate=fate)
    )
    report = run_in_process(runenv, host, lib, runenv.scene(), engine="process", workers=2)
    by = {r.material: r for r in report.results}
    assert by["victim"].status == "failed" and words in by["victim"].error
    assert all(by[f"ok{i}"].status == "ok" for i in range(3))
    assert_consistent(runenv.out)


@pytest.mark.parametrize(
    ("fate", "status", "words"),
    [
        ("raise", "failed", "ValueError: this fabric's step always raises (at runtoy.py:"),
        ("sysexit", "failed", "SystemExit: 4"),
        ("failure", "failed", "the drape placed no cell"),
        ("nan", "failed", "step 'work' gave non-finite numbers: work_value = nan"),
        ("partial", "partial", ""),
    ],
)
def test_case_fates_are_recorded_in_words(runenv, host, fate, status, words):
    lib = runenv.library(fabric("good"), fabric("bad", fate=fate))
    report = run_in_process(runenv, host, lib, runenv.scene())
    by = {r.material: r for r in report.results}
    assert by["good"].status == "ok"
    assert by["bad"].status == status
    assert words in (by["bad"].error or "")
    row = table(runenv.out).set_index("material").loc["bad"]
    assert row["status"] == status
    if fate == "partial":
        assert row["reasons"] == "the net stopped at a crease"
        assert float(row["covered_fraction"]) == 0.25
    if fate == "nan":  # no NaN reaches a file as if it were a result
        assert not (runenv.out / "work-scene" / "bad" / "work.txt").exists()
    assert_consistent(runenv.out)


@pytest.mark.parametrize(("engine", "fate"), [("process", "hang"), ("process", "spin")])
def test_hanging_case_times_out_and_others_finish(runenv, host, engine, fate):
    lib = runenv.library(fabric("quick"), fabric("stuck", fate=fate), fabric("quick2"))
    t0 = time.monotonic()
    report = run_in_process(
        runenv, host, lib, runenv.scene(), engine=engine, workers=2, timeout_s=1.5
    )
    assert time.monotonic() - t0 < 30
    by = {r.material: r for r in report.results}
    assert by["stuck"].status == "timed_out"
    assert by["stuck"].error == "stopped at the case time limit of 1.5 s"
    assert by["quick"].status == by["quick2"].status == "ok"
    assert json.loads((runenv.out / "work-scene/stuck/summary.json").read_text())["status"] == (
        "timed_out"
    )
    assert_consistent(runenv.out)


@pytest.mark.slow
def test_dask_dead_and_hanging_cases_cost_only_themselves(runenv, host):
    lib = runenv.library(
        fabric("stuck", fate="hang"), fabric("dead", fate="exit"), fabric("fine", work_s=0.2)
    )
    report = run_in_process(
        runenv, host, lib, runenv.scene(), engine="dask", workers=2, timeout_s=3
    )
    by = {r.material: r for r in report.results}
    assert by["stuck"].status == "timed_out"
    assert by["dead"].status == "failed" and "died (Dask: KilledWorker)" in by["dead"].error
    assert by["fine"].status == "ok"
    assert_consistent(runenv.out)


def test_serial_hang_times_out_and_scene_limit_wins(runenv, host):
    lib = runenv.library(fabric("stuck", fate="hang"), fabric("quick"))
    scene = runenv.scene(extra="limits: {case_timeout_s: 0.5}\n")
    report = run_in_process(runenv, host, lib, scene, timeout_s=100)
    by = {r.material: r for r in report.results}
    assert by["stuck"].status == "timed_out" and "0.5 s" in by["stuck"].error
    assert by["quick"].status == "ok"
    assert json.loads((runenv.out / "work-scene/quick/summary.json").read_text())[
        "limit_case_timeout_s"
    ] == pytest.approx(0.5)


def test_timed_out_case_in_the_cli_exits_1_and_says_so(runenv):
    lib = runenv.library(fabric("stuck", fate="hang"), fabric("quick"))
    proc = runenv.run(lib, runenv.scene(), "--engine", "serial", "--case-timeout", "0.5")
    assert proc.returncode == 1
    no_traceback(proc)
    assert "TIMED OUT work-scene/stuck: stopped at the case time limit of 0.5 s" in proc.stderr
    assert "1 ok, 1 timed_out" in proc.stdout


def test_partial_and_failed_are_said_at_the_end_of_the_run(runenv):
    lib = runenv.library(fabric("half", fate="partial"), fabric("gone", fate="failure"))
    proc = runenv.run(lib, runenv.scene(), "--engine", "serial")
    assert proc.returncode == 1
    assert (
        "PARTIAL work-scene/half: covers 25.0 % of what the scene asked; the net stopped at a "
        "crease" in proc.stdout
    )
    assert "FAILED work-scene/gone: the drape placed no cell" in proc.stderr
    assert "partial = finite, but covers less than the scene asked" in proc.stdout


def test_skipped_partial_case_stays_partial_in_the_tables(runenv, host):
    lib = runenv.library(fabric("half", fate="partial"))
    run_in_process(runenv, host, lib, runenv.scene())
    report = run_in_process(runenv, host, lib, runenv.scene())
    assert report.results[0].reused and report.counts() == {"skipped": 1}
    assert table(runenv.out)["status"].tolist() == ["partial"]
    assert statuses(runenv.out) == {"work-scene/half": "partial"}


# -- 6. interrupts ---------------------------------------------------------------------------


def _wait_for(predicate, timeout=60.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(0.05)
    return False


def _finished(out: Path) -> dict[str, bytes]:
    found = {}
    for path in out.glob("*/*/summary.json"):
        rec = json.loads(path.read_text())
        if rec["status"] == "ok":
            found[rec["case_id"]] = path.read_bytes()
    return found


@pytest.mark.parametrize(
    ("sig", "engine"),
    [
        (signal.SIGINT, "process"),
        (signal.SIGTERM, "serial"),
        pytest.param(signal.SIGINT, "dask", marks=pytest.mark.slow),
    ],
)
def test_interrupt_stops_promptly_and_keeps_what_finished(runenv, sig, engine):
    # Two quick cases and four that sleep 4 s: the signal lands while cases run however loaded
    # the machine is (six equal 0.5 s cases could all end before it on a busy host).
    quick = [fabric(f"a{i}", work_s=0.2) for i in range(2)]
    long = [fabric(f"f{i}", work_s=4.0) for i in range(4)]
    lib = runenv.library(*quick, *long)
    scene = runenv.scene()
    proc = runenv.start(lib, scene, "--workers", "2", "--engine", engine)
    assert _wait_for(lambda: len(_finished(runenv.out)) >= 2)
    proc.send_signal(sig)
    t0 = time.monotonic()
    _, err = proc.communicate(timeout=30)
    assert time.monotonic() - t0 < 8, "the interrupt was not prompt"
    assert proc.returncode == 130, err
    assert "Traceback" not in err
    assert "INTERRUPTED: finished cases are kept" in err
    kept = _finished(runenv.out)
    st = statuses(runenv.out)
    assert set(st.values()) <= {"ok", "interrupted"} and "interrupted" in st.values(), (st, err)
    assert {k for k, v in st.items() if v == "ok"} == set(kept)
    assert_consistent(runenv.out)
    rerun = runenv.run(lib, scene, "--workers", "2", "--engine", engine)
    assert rerun.returncode == 0, rerun.stderr
    assert f"{len(kept)} skipped" in rerun.stdout
    for case_id, content in kept.items():  # untouched
        assert (runenv.out / case_id / "summary.json").read_bytes() == content
    assert set(statuses(runenv.out).values()) == {"ok"}
    assert_consistent(runenv.out)


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().split()[2] != "Z"
    except OSError:
        return False


@pytest.mark.parametrize("engine", ["process", "dask"])
def test_kill_9_of_the_main_process_takes_its_workers_with_it(runenv, tmp_path, engine):
    if engine == "dask":
        pytest.importorskip("distributed")
    lib = runenv.library(*(fabric(f"f{i}", fate="hang") for i in range(2)))
    proc = runenv.start(lib, runenv.scene(), "--workers", "2", "--engine", engine)
    pids_log = Path(runenv.env["RUNTOY_PIDS"])
    assert _wait_for(lambda: pids_log.exists() and len(pids_log.read_text().split()) >= 2)
    workers = [int(p) for p in pids_log.read_text().split()]
    assert all(_alive(p) for p in workers)
    proc.kill()
    proc.wait(timeout=10)
    assert _wait_for(lambda: not any(_alive(p) for p in workers), timeout=10), workers


def test_a_dask_run_with_nothing_to_do_closes_its_early_cluster_quietly(runenv, host):
    """The command opens its LocalCluster before it knows a rerun has nothing to compute: it
    is closed at exit, and nothing but the run's own words is printed."""
    pytest.importorskip("distributed")
    lib = runenv.library(fabric("f0"), fabric("f1"))
    scene = runenv.scene()
    run_in_process(runenv, host, lib, scene)
    proc = runenv.run(lib, scene, "--engine", "dask", "--workers", "2")
    assert proc.returncode == 0, proc.stderr
    assert "2 skipped" in proc.stdout
    assert "Exception" not in proc.stderr
    no_traceback(proc)


# -- 11. permissions follow the umask ----------------------------------------------------------


@pytest.mark.parametrize("mask", [0o022, 0o077, 0o002])
def test_outputs_follow_the_umask(runenv, host, mask):
    old = os.umask(mask)
    try:
        run_in_process(runenv, host, runenv.library(fabric("a")), runenv.scene())
    finally:
        os.umask(old)
    for name in ("manifest.json", "results.csv", "work-scene/a/summary.json"):
        assert (runenv.out / name).stat().st_mode & 0o777 == 0o666 & ~mask, name


# -- full disk, broken records ---------------------------------------------------------------


def test_full_disk_fails_the_case_and_the_run_says_so(runenv, host, monkeypatch):
    import preform.base.atomic as atomic

    real_fsync = os.fsync
    calls = {"n": 0}

    def fsync(fd):
        calls["n"] += 1
        if calls["n"] >= 2:  # the manifest's first write succeeds, then the disk is full
            raise OSError(errno.ENOSPC, "No space left on device")
        real_fsync(fd)

    monkeypatch.setattr(atomic.os, "fsync", fsync)
    with pytest.raises(OSError, match="No space left"):
        run_in_process(runenv, host, runenv.library(fabric("a")), runenv.scene())
    monkeypatch.setattr(atomic.os, "fsync", real_fsync)
    assert not [p for p in runenv.out.rglob("*") if is_temporary_name(p.name)]
    # the next run, with space again, completes and is consistent
    report = run_in_process(runenv, host, runenv.library(fabric("a")), runenv.scene())
    assert report.results[0].status == "ok"
    assert_consistent(runenv.out)


def test_full_disk_through_the_cli_is_a_clear_error(runenv, monkeypatch):
    from click.testing import CliRunner

    import preform.base.atomic as atomic
    import preform.plugin_manager as pm
    from preform.cli import cli

    for key in ("PYTHONPATH", "PREFORM_LOAD_PLUGINS"):
        monkeypatch.setenv(key, runenv.env[key])
    pm.reset_default_host()

    def fsync(fd):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(atomic.os, "fsync", fsync)
    args = runenv.command(runenv.library(fabric("a")), runenv.scene(), "--engine", "serial")
    result = CliRunner().invoke(cli, args[3:])
    pm.reset_default_host()
    assert result.exit_code == 1
    assert "could not write the results into" in result.output
    assert "No space left on device" in result.output
    assert result.exception is None or isinstance(result.exception, SystemExit)


def test_unreadable_manifest_is_kept_aside_and_the_run_goes_on(runenv, host):
    runenv.out.mkdir()
    (runenv.out / "manifest.json").write_text("this is not JSON {")
    run_in_process(runenv, host, runenv.library(fabric("a")), runenv.scene())
    aside = list(runenv.out.glob("manifest.unreadable-*.json"))
    assert len(aside) == 1 and aside[0].read_text() == "this is not JSON {"
    assert_consistent(runenv.out)


@pytest.mark.parametrize("damage", ["garbage", "empty", "other status", "missing file"])
def test_damaged_case_record_is_redone(runenv, host, damage):
    lib, scene = runenv.library(fabric("a"), fabric("b")), runenv.scene()
    run_in_process(runenv, host, lib, scene)
    summary = runenv.out / "work-scene" / "a" / "summary.json"
    if damage == "garbage":
        summary.write_text("{{{")
    elif damage == "empty":
        summary.write_text("")
    elif damage == "other status":
        summary.write_text(summary.read_text().replace('"ok"', '"failed"'))
    else:
        (runenv.out / "work-scene" / "a" / "work.txt").unlink()
    report = run_in_process(runenv, host, lib, scene)
    by = {r.material: r for r in report.results}
    assert not by["a"].reused and by["a"].status == "ok"
    assert by["b"].reused
    assert (runenv.out / "work-scene" / "a" / "work.txt").is_file()
    assert_consistent(runenv.out)


def test_deleted_case_folder_leaves_the_manifest_and_tables(runenv, host):
    import shutil

    lib = runenv.library(fabric("a"), fabric("b"))
    run_in_process(runenv, host, lib, runenv.scene())
    shutil.rmtree(runenv.out / "work-scene" / "b")
    run_in_process(runenv, host, runenv.library(fabric("a")), runenv.scene())
    assert statuses(runenv.out) == {"work-scene/a": "ok"}
    assert_consistent(runenv.out)


def test_lock_file_names_its_holder(runenv):
    with RunDirectory(runenv.out):
        text = (runenv.out / LOCK_NAME).read_text()
    assert text.startswith(f"pid {os.getpid()}, since ")


def test_atomic_write_that_raises_leaves_the_old_file(tmp_path):
    target = tmp_path / "keep.json"
    target.write_text("old")
    with pytest.raises(RuntimeError), atomic_open(target) as f:
        f.write("new")
        raise RuntimeError("writer failed")
    assert target.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["keep.json"]


def test_plan_order_does_not_depend_on_the_hash_seed():
    code = (
        "from preform.plugin_manager import default_host\n"
        "from preform.pipeline.scene import load_scene, default_scene_path\n"
        "from preform.pipeline.planner import plan\n"
        "h = default_host()\n"
        "s, _ = load_scene(default_scene_path(), h.registry)\n"
        "print(' '.join(x.name for x in plan(s, h.registry)))\n"
    )
    orders = {
        subprocess.run(
            [sys.executable, "-c", code],
            env={**os.environ, "PYTHONHASHSEED": seed},
            capture_output=True,
            text=True,
            timeout=60,
            check=True,
        ).stdout
        for seed in ("1", "2", "3")
    }
    assert len(orders) == 1


def test_interrupt_while_the_library_loads_exits_130_without_traceback(runenv, monkeypatch, capsys):
    import preform.cli
    import preform.library

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(preform.library, "load_library", interrupted)
    args = runenv.command(runenv.library(fabric("a")), runenv.scene(), "--engine", "serial")
    monkeypatch.setattr(sys, "argv", ["preform", *args[3:]])
    with pytest.raises(SystemExit) as info:
        preform.cli.main()
    assert info.value.code == 130
    assert capsys.readouterr().err.strip() == "Aborted!"
    assert not runenv.out.exists()


# -- 7. batches of small cases (issue 15): a lost batch costs only its unfinished cases -----


def _work_runs(runenv) -> int:
    """How many times a runtoy step ran (each run appends its worker's pid)."""
    log = Path(runenv.env["RUNTOY_PIDS"])
    return len(log.read_text().splitlines()) if log.exists() else 0


@pytest.mark.parametrize("fate", ["kill", "exit"])
def test_worker_killed_mid_batch_keeps_the_finished_and_reruns_the_rest(runenv, host, fate):
    # one worker, batches of 4 in library order: [a0, a1, victim, a2] then [a3, a4]; the
    # victim kills its worker after a0 and a1 finished in it
    names = ["a0", "a1", "victim", "a2", "a3", "a4"]
    lib = runenv.library(*(fabric(n, fate=fate if n == "victim" else "ok") for n in names))
    report = run_in_process(
        runenv, host, lib, runenv.scene(), engine="process", workers=1, batch_size=4
    )
    by = {r.material: r for r in report.results}
    assert by["victim"].status == "failed"
    assert "the worker process running this case died" in by["victim"].error
    assert all(by[n].status == "ok" for n in names if n != "victim"), by
    assert all(by[n].results["work_value"] == 1.0 for n in names if n != "victim")
    # a0 and a1 kept from the lost batch, not run again; the victim and a2 ran again alone:
    # 5 runs of the step in the batches (a2 never started in the first) plus 2
    assert _work_runs(runenv) == 5 + 2
    assert_consistent(runenv.out)
    run_id = manifest(runenv.out)["runs"][-1]["id"]
    for n in names:  # every record, the kept ones included, is this run's
        rec = json.loads((runenv.out / "work-scene" / n / "summary.json").read_text())
        assert rec["run_id"] == run_id


def test_hanging_case_in_a_batch_times_out_alone(runenv, host):
    lib = runenv.library(fabric("quick"), fabric("stuck", fate="hang"), fabric("quick2"))
    t0 = time.monotonic()
    report = run_in_process(
        runenv, host, lib, runenv.scene(), engine="process", workers=1, batch_size=3, timeout_s=1.5
    )
    assert time.monotonic() - t0 < 30
    by = {r.material: r for r in report.results}
    assert by["stuck"].status == "timed_out"
    assert by["stuck"].error == "stopped at the case time limit of 1.5 s"
    assert by["quick"].status == by["quick2"].status == "ok"
    assert _work_runs(runenv) == 3  # stopped inside its batch: nothing ran twice
    assert_consistent(runenv.out)


def test_batched_and_unbatched_runs_agree(runenv, host, tmp_path):
    lib = runenv.library(
        *(fabric(f"f{i}", work_s=0.01 * i) for i in range(7)), fabric("bad", fate="raise")
    )
    scene = runenv.scene()
    serial = run_in_process(runenv, host, lib, scene)
    batched = run_in_process(
        runenv, host, lib, scene, engine="process", workers=2, batch_size=3, force=True
    )
    assert [(r.case_id, r.status, r.results, r.error) for r in serial.results] == [
        (r.case_id, r.status, r.results, r.error) for r in batched.results
    ]
    assert_consistent(runenv.out)


@pytest.mark.slow
def test_dask_worker_killed_mid_batch_keeps_the_finished(runenv, host):
    names = ["a0", "a1", "victim", "a2"]
    lib = runenv.library(*(fabric(n, fate="exit" if n == "victim" else "ok") for n in names))
    report = run_in_process(
        runenv, host, lib, runenv.scene(), engine="dask", workers=1, batch_size=4
    )
    by = {r.material: r for r in report.results}
    assert by["victim"].status == "failed" and "Dask: KilledWorker" in by["victim"].error
    assert all(by[n].status == "ok" for n in names if n != "victim")
    assert _work_runs(runenv) == 3 + 2
    assert_consistent(runenv.out)


def test_a_rerun_starts_the_cases_an_earlier_run_found_longest(runenv, host, monkeypatch):
    order = runenv.root / "order.log"
    monkeypatch.setenv("RUNTOY_ORDER", str(order))
    works = {"w0": 0.0, "w3": 0.3, "w1": 0.1, "w2": 0.2}
    lib = runenv.library(*(fabric(n, work_s=w) for n, w in works.items()))
    scene = runenv.scene()
    run_in_process(runenv, host, lib, scene)  # nothing known yet: library order
    assert order.read_text().split() == list(works)
    order.unlink()
    run_in_process(runenv, host, lib, scene, force=True)
    assert order.read_text().split() == ["w3", "w2", "w1", "w0"]
