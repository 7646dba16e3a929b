"""The package as pyproject.toml describes it: every folder of code listed under the one ``mechviz``
namespace, the version from the package's metadata, and nothing POSIX-only imported at load."""

from __future__ import annotations

import subprocess
import sys
import tomllib
from pathlib import Path

import mechviz

ROOT = Path(__file__).resolve().parents[1]


def test_every_folder_of_code_is_a_listed_package():
    conf = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    listed = set(conf["packages"])
    folders = {name: ROOT / where for name, where in conf["package-dir"].items()}
    found = set()
    for name, where in folders.items():
        for init in where.rglob("__init__.py"):
            rel = init.parent.relative_to(where).parts
            found.add(".".join((name, *rel)))
    assert found <= listed, (
        f"folders with an __init__.py missing from [tool.setuptools] packages: {found - listed}"
    )
    # and every listed package has its folder (data folders included)
    for pkg in listed:
        parent = max((n for n in folders if pkg == n or pkg.startswith(n + ".")), key=len)
        path = folders[parent].joinpath(*pkg[len(parent) :].split(".")[1:])
        assert path.is_dir(), (pkg, path)


def test_the_version_is_the_distributions():
    version = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
    assert mechviz.__version__ == version
    got = subprocess.run(
        [sys.executable, "-m", "mechviz.viz.cli", "--version"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert got.returncode == 0 and got.stdout == f"mechviz {version}\n", got.stdout + got.stderr


def test_the_product_imports_and_writes_sets_where_fcntl_does_not_exist(tmp_path):
    code = (
        "import sys; sys.modules['fcntl'] = None\n"
        "import mechviz.dynamics.api, mechviz.dynamics.fileset, mechviz.viz.record\n"
        "import mechviz.viz.notebook, mechviz.viz.cli, mechviz.viz.play\n"
        "from mechviz.dynamics import fileset\n"
        "import hashlib, json, sys\n"
        "b = b'x' * 10\n"
        "man = {'files': {'a.csv': {'bytes': 10, 'sha256': hashlib.sha256(b).hexdigest()}}}\n"
        "fileset.write_set(sys.argv[1], 'a', {'a.csv': b, 'a.json': json.dumps(man).encode()})\n"
        "with fileset.reading(sys.argv[1]):\n"
        "    assert fileset.check_set(sys.argv[1], 'a.json')[1]['a.csv'] == b\n"
        "print('imported')\n"
    )
    got = subprocess.run(
        [sys.executable, "-c", code, str(tmp_path)], capture_output=True, text=True, timeout=300
    )
    assert got.returncode == 0 and got.stdout == "imported\n", got.stderr[-2000:]


def test_the_data_are_package_data():
    from mechviz.dynamics.assets import asset

    demos = asset("demos")
    assert demos == ROOT / "assets" / "demos" or "site-packages" in str(demos)
    assert sorted(p.name for p in demos.glob("*.toml")) == sorted(
        p.name for p in (ROOT / "assets" / "demos").glob("*.toml")
    )
    assert asset("bench", "references.json").is_file() and asset("atlas", "hoop-maps.npz").is_file()
