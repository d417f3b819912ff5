"""The README is a landing page: short, and every link it gives into the documentation leads to a file."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")
MAX_LINES = 70  # about two screens; the reference text lives in docs/ (make docs)


def test_the_readme_fits_on_two_screens() -> None:
    assert len(README.splitlines()) <= MAX_LINES


def test_every_relative_link_and_picture_of_the_readme_exists() -> None:
    targets = re.findall(r"\]\(([^)#]+)(?:#[^)]*)?\)", README)
    local = [t for t in targets if "://" not in t]
    assert local, "the README links into the documentation"
    missing = [t for t in local if not (ROOT / t).exists()]
    assert not missing, f"README links to missing files: {missing}"


def test_the_readme_keeps_its_two_commands() -> None:
    assert "make run" in README and "make test" in README
