"""What a user who clones, installs, cites or extends preform relies on being in the repository."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[2]
DOCS = [ROOT / "README.md", ROOT / "CONTRIBUTING.md", *sorted((ROOT / "docs").glob("*.md"))]


def test_license_is_the_one_pyproject_declares():
    declared = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["license"]
    assert declared == {"text": "MIT"}
    text = (ROOT / "LICENSE").read_text()
    assert text.startswith("MIT License") and "WITHOUT WARRANTY OF ANY KIND" in text


def test_citation_names_the_software_and_the_founding_paper():
    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text())
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert cff["cff-version"] == "1.2.0" and cff["type"] == "software"
    assert cff["version"] == project["version"]
    assert cff["license"] == "MIT"
    (paper,) = [r for r in cff["references"] if "fibre architecture" in r["title"]]
    assert paper["title"] == (
        "Effects of fibre architecture on deformation during preform manufacture"
    )
    families = [a.get("family-names") for a in paper["authors"]]
    assert families[:4] == ["Souter", "Long", "Robitaille", "Rudd"]


def test_changelog_has_an_unreleased_section_and_the_current_version():
    text = (ROOT / "CHANGELOG.md").read_text()
    version = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
    assert "## [Unreleased]" in text and f"## [{version}]" in text


def test_the_package_is_marked_typed_and_ships_the_marker():
    assert (ROOT / "core" / "py.typed").is_file()
    data = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    assert "py.typed" in data["package-data"]["preform"]


def test_every_package_folder_is_a_listed_package():
    """A package folder missing from ``[tool.setuptools] packages`` is left out of a wheel."""
    data = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    folders = {
        "preform": ROOT / "core",
        "preform.plugins": ROOT / "plugins",
    }
    found = set()
    for name, root in folders.items():
        for init in root.rglob("__init__.py"):
            parts = init.parent.relative_to(root).parts
            found.add(".".join([name, *parts]))
    assert found <= set(data["packages"]), sorted(found - set(data["packages"]))


def test_every_relative_link_in_the_docs_points_into_the_repository():
    """CONTRIBUTING once sent readers to a design page outside the repository."""
    broken = []
    for doc in DOCS:
        for target in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", doc.read_text()):
            if re.match(r"[a-z]+://", target):
                continue
            path = (doc.parent / target).resolve()
            if not path.is_relative_to(ROOT) or not path.exists():
                broken.append(f"{doc.name}: {target}")
    assert not broken, broken


def test_build_artefacts_are_not_tracked():
    import subprocess

    tracked = subprocess.run(
        ["git", "ls-files"], cwd=ROOT, capture_output=True, text=True, check=True
    ).stdout.split()
    assert not [p for p in tracked if ".egg-info" in p or "__pycache__" in p]


def test_the_cell_status_legend_matches_the_code():
    from preform.drape.engine.result import CellStatus

    text = (ROOT / "docs" / "results.md").read_text()
    for status in CellStatus:
        assert f"| `{status.name}` | {int(status)} |" in text
