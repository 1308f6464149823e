"""Writers beside a run (issue 25, item 1): a run cleans its directory of the temporaries
killed writers left, and no live writer's temporary may go with them, whoever the writer is
(``preform export``, a script, another run) and whatever lock it holds or does not hold.

The mechanism (``preform.base.atomic``): a writer holds a flock on its temporary until it is
renamed into place; the clean-up removes only temporaries it can lock.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import pytest

from preform.base.atomic import atomic_open, is_temporary_name, remove_stale_temporaries
from preform.pipeline.rundir import RunDirectory


def _temporaries(folder: Path) -> list[Path]:
    return [p for p in folder.rglob("*") if is_temporary_name(p.name)]


def test_a_live_writers_temporary_survives_the_clean_up(tmp_path):
    """In this process: the clean-up runs while the temporary is open, and the write lands."""
    target = tmp_path / "deep" / "table.csv"
    with atomic_open(target) as f:
        f.write("a,b\n")
        (left,) = _temporaries(tmp_path)
        assert remove_stale_temporaries(tmp_path) == []
        assert left.exists()
        f.write("1,2\n")
    assert target.read_text() == "a,b\n1,2\n"
    assert _temporaries(tmp_path) == []


def test_a_dead_writers_temporary_is_removed(tmp_path):
    """The lock dies with its writer: what a killed process left is still cleaned."""
    target = tmp_path / "half.json"
    code = (
        "import os\n"
        "from preform.base.atomic import atomic_open\n"
        f"with atomic_open({str(target)!r}) as f:\n"
        "    f.write('{')\n"
        "    f.flush()\n"
        "    os._exit(9)\n"
    )
    subprocess.run([sys.executable, "-c", code], check=False, timeout=60)
    (left,) = _temporaries(tmp_path)
    assert remove_stale_temporaries(tmp_path) == [left]
    assert not left.exists() and not target.exists()


def test_a_run_entering_and_leaving_keeps_another_processs_write(tmp_path):
    """What ``preform export`` does beside a run, made deterministic: another process holds
    its temporary open (it writes without the run lock) while a run takes the directory,
    cleans it at its start and at its end; then it finishes its write."""
    target = tmp_path / "cut_pattern.csv"
    go = tmp_path / "go"
    code = textwrap.dedent(
        f"""
        import os, sys, time
        from pathlib import Path
        from preform.base.atomic import atomic_open
        with atomic_open({str(target)!r}) as f:
            f.write("x,y\\n")
            f.flush()
            print("open", flush=True)
            while not Path({str(go)!r}).exists():
                time.sleep(0.01)
            f.write("1,2\\n")
        """
    )
    writer = subprocess.Popen(
        [sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    try:
        assert writer.stdout is not None and writer.stdout.readline() == "open\n"
        with RunDirectory(tmp_path):  # cleans at entering and at leaving
            pass
        assert len(_temporaries(tmp_path)) == 1
        go.touch()
        _, err = writer.communicate(timeout=60)
    finally:
        if writer.poll() is None:
            writer.kill()
            writer.wait()
    assert writer.returncode == 0, err
    assert target.read_text() == "x,y\n1,2\n"


def test_writes_racing_a_clean_up_loop_all_land(tmp_path):
    """Many writes while another thread cleans the folder as fast as it can: the moment
    between a temporary's creation and its lock included, none is lost (before issue 25 one
    in a few hundred died with FileNotFoundError on its temporary)."""
    stop = threading.Event()
    removed: list[Path] = []

    def clean() -> None:
        while not stop.is_set():
            removed.extend(remove_stale_temporaries(tmp_path))

    cleaner = threading.Thread(target=clean)
    cleaner.start()
    try:
        for i in range(200):
            with atomic_open(tmp_path / f"f{i % 7}.txt") as f:
                f.write(str(i))
    finally:
        stop.set()
        cleaner.join()
    assert {p.read_text() for p in tmp_path.glob("f*.txt")} == {str(i) for i in range(193, 200)}
    assert removed == [] or all(not p.exists() for p in removed)
    assert _temporaries(tmp_path) == []


SMALL_DOME = """\
name: small-dome
tool: {surface: hemisphere, radius_mm: 60}
ply: {node_spacing_mm: 10, size_mm: [200, 200]}
start: {point_mm: [0, 0], orientation_deg: 0, generator_angle_deg: 90, generators: geodesic}
outputs: [drape, cells_csv]
"""


def _cli(*args: str) -> subprocess.Popen[str]:
    env = {k: v for k, v in os.environ.items() if k != "PREFORM_LIBRARY"}
    return subprocess.Popen(
        [sys.executable, "-m", "preform", *args],
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


@pytest.mark.slow
def test_export_and_run_into_one_folder_lose_nothing(tmp_path):
    """The issue's trial, 20 times: ``preform export`` and ``preform pipeline run`` into one
    folder at once (a small dome, about 3 s each). Before issue 25 one export in three died
    with exit 3, FileNotFoundError on its ``.preform-tmp`` file."""
    scene = tmp_path / "small.yaml"
    scene.write_text(SMALL_DOME)
    for trial in range(20):
        out = tmp_path / f"out{trial}"
        run = _cli("pipeline", "run", "--scene", str(scene), "--materials", "plain-weave-150",
                   "--workers", "1", "--out", str(out))  # fmt: skip
        time.sleep(0.05 * (trial % 10))  # the export's writes land at different moments of the run
        export = _cli("export", "plain-weave-150", "cut-pattern", "--scene", str(scene),
                      "--out", str(out))  # fmt: skip
        _, export_err = export.communicate(timeout=300)
        _, run_err = run.communicate(timeout=300)
        assert export.returncode == 0, (trial, export_err)
        assert run.returncode == 0, (trial, run_err)
        assert "Traceback" not in export_err + run_err
        for name in ("cut_pattern.csv", "cut_pattern.dxf", "cut_pattern.svg"):
            assert (out / name).stat().st_size > 0, (trial, name)
        assert (out / "small-dome" / "plain-weave-150" / "summary.json").is_file()
        assert _temporaries(out) == []
