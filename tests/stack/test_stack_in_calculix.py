"""A layup's composite sections, as the pipeline writes them (``stack_calculix``), run in
CalculiX: ccx reads the deck, applies it (no *ERROR), and the plate's answer scales with the
plies' material exactly as linear elasticity says (all moduli × k: displacements ÷ k), so the
materials the deck names are the ones its sections use.

The writers alone are checked against laminate theory in tests/export/test_calculix_solver.py;
here the mesh is the S8R cap of docs/examples/calculix_cap_mesh.inp (ccx takes composite
shell sections on S8R and S6 only).
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import numpy as np

import preform

EXAMPLES = Path(__file__).resolve().parents[2] / "docs" / "examples"
FABRICS = ("plain-weave-600", "satin-4hs-crowfoot")
#: An illustrative orthotropic ply (MPa): E1, E2, E3, ν12, ν13, ν23, G12, G13, G23.
MODULI = (140000.0, 10000.0, 10000.0, 0.3, 0.3, 0.5, 5000.0, 5000.0, 3500.0)
RATIOS = (3, 4, 5)  # the Poisson ratios, which do not scale


def job(scale: float) -> str:
    """The cap held at its rim, pushed at its pole; every fabric's moduli times ``scale``."""
    v = [m if k in RATIOS else m * scale for k, m in enumerate(MODULI)]
    card = ", ".join(f"{x:.6g}" for x in v[:8]) + f"\n{v[8]:.6g}, 0.\n"
    materials = "".join(
        f"*MATERIAL, NAME={name}\n*ELASTIC, TYPE=ENGINEERING CONSTANTS\n{card}" for name in FABRICS
    )
    return (
        "*INCLUDE, INPUT=calculix_cap_mesh.inp\n"
        + materials
        + "*INCLUDE, INPUT=stack_calculix.inp\n*BOUNDARY\nRIM, 1, 3\n*STEP\n*STATIC\n"
        "*CLOAD\nPOLE, 1, 1.\n*NODE PRINT, NSET=POLE\nU\n*END STEP\n"
    )


def pole(output_dat: str) -> np.ndarray:
    numbers = re.findall(r"^\s*\d+\s+(\S+)\s+(\S+)\s+(\S+)\s*$", output_dat, re.M)
    assert numbers, output_dat[-2000:]
    return np.array([float(v) for v in numbers[-1]])


def test_the_pipelines_stack_deck_runs_in_calculix(tmp_path: Path, ccx, cap_layup) -> None:
    scene = cap_layup(
        [(FABRICS[0], 0), (FABRICS[1], 45)],
        str(EXAMPLES / "calculix_cap_mesh.inp"),
        ["layup", "stack_sections", "stack_calculix"],
    )
    stack = preform.layup(scene, out_dir=tmp_path / "run")
    assert stack.status == "ok", stack.error or stack.reasons
    counts = stack.summary["stack_sections_summary"]
    assert counts["elements_all_plies"] == counts["elements"] == 64  # the cap lies under both
    moved = []
    for scale in (1.0, 4.0):
        folder = tmp_path / f"ccx-{scale:g}"
        folder.mkdir()
        shutil.copy(EXAMPLES / "calculix_cap_mesh.inp", folder)
        shutil.copy(stack.case_dir / "stack_calculix.inp", folder)
        (folder / "cap.inp").write_text(job(scale))
        ccx(folder, "cap")
        moved.append(pole((folder / "cap.dat").read_text()))
    assert np.all(np.isfinite(moved[0])) and abs(moved[0][0]) > 0
    np.testing.assert_allclose(moved[1], moved[0] / 4.0, rtol=1e-5, atol=1e-12)
