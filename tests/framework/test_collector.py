"""The garbage collector is paused while the ``preform`` command starts and on when it computes
(preform.collector). Each command runs in its own interpreter: pausing and freezing are
process-wide, and this test process must keep its own collector as it is."""

from __future__ import annotations

import gc
import json
import os
import subprocess
import sys
import textwrap

from preform.collector import end_startup, startup_phase

# Counts the collections that start while the command runs, and where the collector stood at
# the moments that matter; printed as JSON on stderr's last line.
PROBE = textwrap.dedent(
    """
    import gc, json, os, sys
    seen = {"collections": 0, "case_gc": []}

    def count(phase, info):
        if phase == "start":
            seen["collections"] += 1

    if "pipeline" in sys.argv:  # imported here only for a run: a listing imports nothing first
        from preform.pipeline import runner

        def execute_case(*args, _case=runner.execute_case, **kwargs):
            seen["case_gc"].append(gc.isenabled())
            return _case(*args, **kwargs)

        runner.execute_case = execute_case
    gc.callbacks.append(count)
    if os.environ.get("PROBE_ENTRY") == "cli":  # the command without its entry point's pause
        from preform.cli import main
    else:
        from preform.__main__ import main
    sys.argv = ["preform", *sys.argv[1:]]
    try:
        main()
    except SystemExit as exit:
        seen["exit"] = exit.code
    seen["gc_on_at_end"] = gc.isenabled()
    seen["frozen"] = gc.get_freeze_count()
    print(json.dumps(seen), file=sys.stderr)
    """
)


def run_preform(*args: str, entry: str = "main") -> dict:
    env = {**os.environ, "PROBE_ENTRY": entry}
    done = subprocess.run(
        [sys.executable, "-c", PROBE, *args], capture_output=True, text=True, timeout=300, env=env
    )
    assert done.returncode == 0, done.stderr
    return json.loads(done.stderr.strip().splitlines()[-1])


def test_listing_the_library_is_almost_never_collected():
    """`materials list` is start-up but for its printing: imports, the plugin host, the
    library read. Entered without the entry point's pause, the same listing starts some 60-80
    collections (measured); with it, the few that printing the listing starts."""
    paused = run_preform("materials", "list")
    unpaused = run_preform("materials", "list", entry="cli")
    assert unpaused["collections"] >= 30
    assert paused["collections"] <= unpaused["collections"] // 10
    assert paused["frozen"] > 10_000  # start-up's objects, frozen when it ended
    assert unpaused["frozen"] == 0


def test_a_run_computes_its_cases_with_the_collector_on(tmp_path):
    """Reading the library and the scenes and planning pause the collector; the cases it then
    runs in this process (serial engine) run with it on, so their cyclic garbage is freed."""
    seen = run_preform(
        "pipeline", "run", "--scene", "shear", "--engine", "serial", "--out", str(tmp_path)
    )
    assert seen.get("exit") in (None, 0)
    assert seen["case_gc"] and all(seen["case_gc"])
    assert seen["gc_on_at_end"]
    assert seen["collections"] > 0  # the cases' garbage was collected


def test_a_plugin_or_other_command_body_runs_with_the_collector_on():
    """The entry point's pause ends once the command is known, before its body: `schema`
    prints a JSON schema with the collector on."""
    seen = run_preform("schema")
    assert seen["gc_on_at_end"]


def test_outside_the_command_a_startup_phase_changes_nothing():
    """The Python API and tests invoke the command's code in their own process: nothing is
    paused and nothing frozen there (freezing would keep that process's garbage for good)."""
    assert gc.isenabled()
    frozen = gc.get_freeze_count()
    with startup_phase():
        assert gc.isenabled()
        with startup_phase():
            assert gc.isenabled()
    end_startup()
    assert gc.isenabled()
    assert gc.get_freeze_count() == frozen


def test_in_the_command_nested_phases_end_with_the_outermost():
    """The library read inside `pipeline run`'s planning is one phase with it: the collector
    stays off until the outer phase ends, then the phase's objects are frozen."""
    script = textwrap.dedent(
        """
        import gc, json
        from preform import collector
        states = []
        collector.pause_for_startup()      # the entry point
        states.append(gc.isenabled())
        collector.end_startup()            # the command is known
        states.append(gc.isenabled())
        frozen = gc.get_freeze_count()
        with collector.startup_phase():
            states.append(gc.isenabled())
            with collector.startup_phase():
                kept = [[i] for i in range(5000)]  # objects the phase makes
            states.append(gc.isenabled())
        states.append(gc.isenabled())
        print(json.dumps({"states": states, "more_frozen": gc.get_freeze_count() - frozen}))
        """
    )
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    seen = json.loads(done.stdout)
    assert seen["states"] == [False, True, False, False, True]
    assert seen["more_frozen"] >= 5001  # the 5000 lists the phase made, and the list of them
