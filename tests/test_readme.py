"""The README's Python example runs as printed."""

import re
from pathlib import Path


def test_readme_example_runs(capsys):
    text = (Path(__file__).parents[1] / "README.md").read_text()
    code = re.search(r"```python\n(.*?)```", text, re.S).group(1)
    exec(compile(code, "README.md", "exec"), {})
    settling, overshoot = capsys.readouterr().out.strip().split("] [")
    assert "nan" not in settling
