"""The package as a typed library: a plugin written from the docs passes ``mypy --strict``
against mresim_phys found as an installed package (its ``py.typed`` marker)."""

from __future__ import annotations

import re
import sys
import venv
from pathlib import Path

import pytest

ROOT = Path(__file__).parent.parent
EXAMPLES = {  # module name -> (guide, python block)
    "my_strategies": ("writing-a-strategy.md", 0),
    "my_parts": ("writing-a-strategy.md", 1),
    "my_payloads": ("writing-a-strategy.md", 2),
    "my_columns": ("metric-columns.md", 0),
}


def python_block(guide: str, index: int) -> str:
    text = (ROOT / "docs" / guide).read_text(encoding="utf-8")
    return str(re.findall(r"```python\n(.*?)```", text, re.S)[index])


def installed_copy(tmp_path: Path) -> Path:
    """A Python whose site-packages finds mresim_phys as an installed package (a path
    entry in a .pth file, as mypy reads them), the way a plugin author's project sees it."""
    env = tmp_path / "venv"
    venv.create(env, system_site_packages=True, with_pip=False)
    lib = next((env / "lib").glob("python3*")) / "site-packages"
    packages = tmp_path / "packages"
    packages.mkdir()
    (packages / "mresim_phys").symlink_to(ROOT / "mresim_phys", target_is_directory=True)
    (lib / "mresim_here.pth").write_text(f"{packages}\n", encoding="utf-8")
    return env / "bin" / "python"


@pytest.mark.slow
@pytest.mark.skipif(sys.platform == "win32", reason="a POSIX venv layout")
def test_plugins_written_from_the_docs_pass_mypy_strict(tmp_path: Path) -> None:
    api = pytest.importorskip("mypy.api")
    python = installed_copy(tmp_path)
    plugin = tmp_path / "plugin"
    plugin.mkdir()
    files = []
    for module, (guide, index) in EXAMPLES.items():
        path = plugin / f"{module}.py"
        path.write_text(python_block(guide, index), encoding="utf-8")
        files.append(str(path))
    args = ["--strict", "--python-executable", str(python), "--cache-dir", str(tmp_path / "c")]
    out, err, status = api.run([*args, "--no-site-packages", "--version"])  # mypy runs
    assert status == 0, err
    out, err, status = api.run([*args, *files])
    assert status == 0, out + err
    assert "Success" in out
