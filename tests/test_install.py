"""A wheel built from the repository serves the page, the report and the docs from a fresh venv.

The wheel is built offline (``pip wheel --no-deps --no-build-isolation``, with the setuptools of
the test extras) from a copy of the source tree, installed with ``--no-deps`` into a new venv in
a temporary directory outside the checkout. The dependencies come from this venv's
site-packages, named as plain directories in a ``.pth`` file of the new venv: ``.pth`` files
inside them are not executed, so the checkout's editable-install finder stays off and ``app``
can only come from the wheel. ``pelvic-walk serve`` then runs from the temporary directory,
on free localhost ports, and is stopped at the end (SIGINT, then kill).
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path

import httpx
import pytest

from app.bench.local_server import local_server

ROOT = Path(__file__).resolve().parents[1]
CODE = ("app", "controller", "models", "pelvic_walk")  # the Python packages' top directories
SOURCES = ["pyproject.toml", "README.md", *CODE, "static", "report"]
DATA_PACKAGES = {"app.static": "static", "app.reference_report": "report"}


def _run(cmd: list[str], **kwargs) -> str:
    kwargs.setdefault("env", {k: v for k, v in os.environ.items() if k != "PYTHONPATH"})
    # (a guard against a hang, not a speed target: builds and installs on a busy machine)
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=1800, **kwargs)
    assert proc.returncode == 0, f"{cmd}: {proc.stdout[-2000:]}{proc.stderr[-3000:]}"
    return proc.stdout


def _checkout_packages() -> dict[str, str]:
    """Every package of the checkout (dotted name -> its directory in the wheel)."""
    found = {}
    for top in CODE:
        for init in (ROOT / top).rglob("__init__.py"):
            rel = init.parent.relative_to(ROOT)
            if "__pycache__" not in rel.parts:
                found[".".join(rel.parts)] = rel.as_posix()
    found.update({name: name.replace(".", "/") for name in DATA_PACKAGES})
    return found


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    """The wheel, built from a copy of the tree (no build/ or egg-info left in the checkout)."""
    tmp = tmp_path_factory.mktemp("wheel")
    src = tmp / "src"
    src.mkdir()
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc", "*.egg-info")
    for name in SOURCES:
        path = ROOT / name
        if path.is_dir():
            shutil.copytree(path, src / name, ignore=ignore)
        else:
            shutil.copy2(path, src / name)
    _run(
        [
            sys.executable,
            "-m",
            "pip",
            "wheel",
            "--no-deps",
            "--no-build-isolation",
            "--no-cache-dir",
            "-w",
            str(tmp / "dist"),
            str(src),
        ]
    )
    (found,) = (tmp / "dist").glob("pelvic_walk-*.whl")
    return found


def test_the_wheel_holds_every_package_and_its_files(wheel):
    names = set(zipfile.ZipFile(wheel).namelist())
    packages = _checkout_packages()
    missing = [pkg for pkg, d in packages.items() if f"{d}/__init__.py" not in names]
    assert not missing, f"add {missing} to [tool.setuptools] packages in pyproject.toml"
    sources = {
        **{top: top for top in CODE},
        **{d: name.replace(".", "/") for name, d in DATA_PACKAGES.items()},
    }
    unshipped = [
        f"{src}/{rel}"
        for src, dest in sources.items()
        for path in (ROOT / src).rglob("*")
        if path.is_file()
        and "__pycache__" not in path.parts
        and path.suffix != ".pyc"
        and f"{dest}/{(rel := path.relative_to(ROOT / src).as_posix())}" not in names
    ]
    assert not unshipped, f"add {unshipped} to [tool.setuptools.package-data] in pyproject.toml"
    for rel in (
        "app/static/index.html",
        "app/reference_report/report.md",
        "app/reference_report/results.json",
        "models/dyros_jet/scene.xml",
    ):
        assert rel in names


@pytest.fixture(scope="module")
def venv(wheel, tmp_path_factory) -> Path:
    """A new venv outside the checkout with the wheel, dependencies from this venv."""
    home = tmp_path_factory.mktemp("fresh")
    assert ROOT not in home.parents
    env_dir = home / "venv"
    _run([sys.executable, "-m", "venv", "--without-pip", str(env_dir)])
    python = env_dir / "bin" / "python"
    _run(
        [
            sys.executable,
            "-m",
            "pip",
            "--python",
            str(python),
            "install",
            "--no-deps",
            "--no-index",
            str(wheel),
        ]
    )
    site = Path(
        _run(
            [str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"]
        ).strip()
    )
    ours = Path(sysconfig.get_paths()["purelib"])
    dirs = [ours, ours / "cmeel.prefix" / "lib" / "python3.11" / "site-packages"]  # pinocchio
    (site / "zz_dependencies.pth").write_text(
        "".join(f"{d}\n" for d in dirs if d.is_dir()), encoding="utf-8"
    )
    return env_dir


def _clean_env(home: Path) -> dict[str, str]:
    env = {
        k: v
        for k, v in os.environ.items()
        if not k.startswith("PELVIC_WALK_") and k not in ("PYTHONPATH", "VIRTUAL_ENV")
    }
    env["XDG_STATE_HOME"] = str(home / "state")  # no recorded report: the packaged one
    env["PELVIC_WALK_DISPLAY_NICE"] = "0"  # full priority beside another pytest process
    return env


def test_app_comes_from_the_wheel(venv):
    home = venv.parent
    code = (
        "import sys, app, app.static, app.reference_report, fastapi_offline, pinocchio\n"
        "import pelvic_walk\n"
        "print(app.__file__); print(app.static.__file__); print(app.reference_report.__file__)\n"
        "print(pelvic_walk.__file__)\n"
        "print(any('__editable__' in m for m in sys.modules))\n"
    )
    out = _run([str(venv / "bin" / "python"), "-c", code], cwd=home, env=_clean_env(home))
    *files, editable = out.split()
    assert all(Path(f).is_relative_to(venv) for f in files), files
    assert editable == "False"


def test_serve_from_the_installed_wheel(venv):
    home = venv.parent
    exe = venv / "bin" / "pelvic-walk"
    with local_server(exe=exe, env=_clean_env(home), cwd=home) as server:
        base, viser_port = server.base, server.viser_port
        with httpx.Client(base_url=base, timeout=60) as client:
            page = client.get("/")
            assert page.status_code == 200 and "<title>pelvic-walk" in page.text
            assert f":{viser_port}/" in page.text

            report = client.get("/report")
            assert report.status_code == 200 and "<table>" in report.text
            figures = re.findall(r'<img src="(/report/figures/[^"]+\.png)"', report.text)
            assert figures
            figure = client.get(figures[0])
            assert figure.status_code == 200 and figure.content.startswith(b"\x89PNG")

            docs = client.get("/docs")
            assert docs.status_code == 200
            assets = re.findall(r'(?:src|href)="([^"]+\.(?:js|css))"', docs.text)
            assert {a.rsplit("/", 1)[-1] for a in assets} >= {
                "swagger-ui-bundle.js",
                "swagger-ui.css",
            }
            for asset in assets:
                assert asset.startswith("/"), f"{asset} is not served locally"
                r = client.get(asset)
                assert r.status_code == 200 and len(r.content) > 10_000, asset
            assert "/api/params" in client.get("/openapi.json").json()["paths"]
