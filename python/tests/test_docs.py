"""docs/python.md's tour runs as written (in a temporary folder, the repository's maps linked)."""

import os
import re
import runpy

from conftest import ROOT


def test_the_tour_in_docs_python_md_runs(tmp_path, monkeypatch, capsys):
    text = (ROOT / "docs" / "python.md").read_text()
    tour = re.search(r"## A tour.*?```python\n(.*?)```", text, re.S).group(1)
    (tmp_path / "envmaps").symlink_to(ROOT / "envmaps")
    script = tmp_path / "tour.py"
    script.write_text(tour)
    monkeypatch.chdir(tmp_path)
    runpy.run_path(str(script))
    assert "('sun', 0.53)" in capsys.readouterr().out
    for png in ("sun.png", "film.png"):
        assert os.path.getsize(tmp_path / png) > 10_000
