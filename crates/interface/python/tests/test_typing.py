"""The type stubs are complete: mypy checks the documented code (the Python blocks of the
README and of docs/python.md) and every example in examples/python against them, and
rejects a call the stubs do not allow (so the check can fail: a keyword the package does
not take, a wrong type); stubtest compares the stubs with the compiled core; and the
documented use runs."""

import re
import subprocess
import sys

import pytest

from conftest import REPO

pytest.importorskip("mypy")

# the imports the stubs do not cover (no type information of their own) are Any
CONFIG = """\
[mypy]
check_untyped_defs = True
warn_unused_ignores = True
[mypy-control.*,dask.*,distributed.*,gwinc.*,matplotlib.*,finesse.*,h5py.*]
ignore_missing_imports = True
follow_imports = skip
"""

# calls the stubs must refuse, each with the error mypy gives it
WRONG = [
    ('pendkit.Model("quad").fit("measured.csv", ["m1"], jacobain="exact")',
     'Unexpected keyword argument "jacobain"'),
    ('pendkit.Model("quad").fit("measured.csv", ["m1"], jacobian="adjoint")',
     'Argument "jacobian"'),
    ('pendkit.Model("quad").run().tf("x00", 3, [1.0])', 'Argument 2 to "tf"'),
    ('pendkit.sweep(pendkit.Model("quad"), {"m3": [40.0]}, client=None, chunk=5)',
     'Unexpected keyword argument "chunk"'),
    ('x: int = pendkit.Model("quad").run().modes().frequencies', "Incompatible types"),
]


def python_blocks(path):
    """The ```python blocks of a Markdown file."""
    return re.findall(r"^```python\n(.*?)^```", path.read_text(), re.S | re.M)


def test_documented_code_and_examples_type_check(tmp_path):
    files = []
    for doc in [REPO / "README.md", REPO / "docs" / "python.md"]:
        for k, block in enumerate(python_blocks(doc)):
            path = tmp_path / f"{doc.stem.replace('.', '_').lower()}_{k}.py"
            path.write_text(block)
            files.append(path)
    assert any(f.name.startswith("python_") for f in files), "docs/python.md has no code"
    examples = sorted((REPO / "examples" / "python").glob("*.py"))
    assert {e.name for e in examples} >= {"damping_loop.py", "dask_sweep.py", "fit_measured.py"}
    wrong = tmp_path / "wrong.py"
    wrong.write_text("import pendkit\n" + "".join(f"{line}\n" for line, _ in WRONG))
    config = tmp_path / "mypy.ini"
    config.write_text(CONFIG)
    done = subprocess.run(
        [sys.executable, "-m", "mypy", "--config-file", str(config),
         "--cache-dir", str(tmp_path / "cache"), *map(str, files + examples + [wrong])],
        capture_output=True, text=True, cwd=tmp_path)
    errors = [line for line in done.stdout.splitlines() if ": error: " in line]
    # every error is one of the wrong calls, each on its line, and every one is reported
    # (mypy names the files relative to its working folder, tmp_path)
    elsewhere = [e for e in errors if not e.startswith("wrong.py:")]
    assert not elsewhere, done.stdout
    for line, (code, message) in enumerate(WRONG, start=2):
        assert any(e.startswith(f"wrong.py:{line}:") and message in e for e in errors), (
            code, done.stdout)


def test_the_stubs_match_the_compiled_core(tmp_path):
    # mypy's stubtest compares every name, class and signature of the stubs with the
    # objects the installed package has at run time: one missing (a `jacobian=`), or one
    # the stubs have and the package does not, is an error
    done = subprocess.run(
        [sys.executable, "-m", "mypy.stubtest", "pendkit._pendkit", "pendkit._results",
         "pendkit._sweep"],
        capture_output=True, text=True, cwd=tmp_path)
    assert done.returncode == 0, done.stdout + done.stderr


def test_the_documented_use_runs(monkeypatch):
    # docs/python.md's first block, as a user runs it from the repository's root (its fit
    # reads examples/python/measured.csv); the sweeps block needs a running scheduler
    monkeypatch.chdir(REPO)
    code = python_blocks(REPO / "docs" / "python.md")[0]
    scope: dict = {}
    exec(compile(code, "docs/python.md", "exec"), scope)
    assert scope["hz"].shape == (200, 24)
    assert {p["name"] for p in scope["fit"]["parameters"]} == {"m1", "l1"}
