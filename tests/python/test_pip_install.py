"""pip installs the module from the build tree into a virtual environment, and the
installed package works there: pip from Debian (python3-pip, python3-venv), no network."""

import os
import pathlib
import subprocess
import sys

BUILD = pathlib.Path(os.environ["VISPROXY_BUILD_DIR"])


def test_pip_install_into_a_venv_and_build_a_proxy(tmp_path):
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", str(venv)], check=True)
    python = venv / "bin" / "python"
    subprocess.run([str(python), "-m", "pip", "install", "--no-build-isolation", "--no-deps", "--no-index", "--quiet",
                    str(BUILD / "python-package")], check=True, cwd=tmp_path)
    script = """
import visproxy, numpy
print(visproxy.__file__)
print(visproxy.__version__)
vertices = numpy.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
triangles = numpy.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]], dtype=numpy.uint32)
proxies = visproxy.build(vertices, triangles, ["aabb"])
print(proxies[0]["name"], proxies[0]["manifest"]["primitives"])
try:
    visproxy.build(vertices, triangles, ["nonsense"])
except visproxy.Error as error:
    print("refused:", type(error).__name__)
"""
    # Run away from the build tree so that only the installed package can be imported.
    env = {key: value for key, value in os.environ.items() if key != "PYTHONPATH"}
    result = subprocess.run([str(python), "-c", script], check=True, capture_output=True, text=True, cwd=tmp_path, env=env)
    lines = result.stdout.splitlines()
    assert str(venv) in lines[0], lines[0]
    assert lines[2] == "aabb 1", result.stdout
    assert lines[3].startswith("refused:"), result.stdout
    # pip knows it, and removes it.
    shown = subprocess.run([str(python), "-m", "pip", "show", "visproxy"], check=True, capture_output=True, text=True)
    assert "Name: visproxy" in shown.stdout and f"Version: {lines[1]}" in shown.stdout, shown.stdout
    subprocess.run([str(python), "-m", "pip", "uninstall", "--yes", "--quiet", "visproxy"], check=True)
    gone = subprocess.run([str(python), "-c", "import visproxy"], capture_output=True, text=True, cwd=tmp_path, env=env)
    assert gone.returncode != 0
