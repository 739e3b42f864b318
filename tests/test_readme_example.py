"""The README's complete example runs as printed there: its code block, run as a script in a
fresh process, prints exactly the README's expected output (rounded so that no CPU's
rounding changes a digit: the positions to 1e-4 m, the errors to one digit)."""
import os
import re
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def example_and_output():
    with open(os.path.join(ROOT, "README.md"), encoding="utf-8") as f:
        text = f.read()
    section = text.split("## A complete example", 1)[1].split("\n## ", 1)[0]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    expected = re.search(r"```text\n(.*?)```", section, re.S).group(1)
    return code, expected


def test_readme_example_prints_what_the_readme_shows(tmp_path):
    code, expected = example_and_output()
    script = tmp_path / "example.py"
    script.write_text(code, encoding="utf-8")
    env = dict(os.environ)
    env["PYTHONPATH"] = ROOT + os.pathsep + env.get("PYTHONPATH", "")
    proc = subprocess.run([sys.executable, str(script)], cwd=tmp_path, env=env, capture_output=True, text=True,
                          timeout=900)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert proc.stdout == expected, (proc.stdout, expected)


def test_readme_is_short():
    """A newcomer reads it in five minutes: at most about 250 lines; the rest is in docs/."""
    with open(os.path.join(ROOT, "README.md"), encoding="utf-8") as f:
        assert len(f.read().splitlines()) <= 250
