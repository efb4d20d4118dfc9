"""The source tree's layout (cmake/check_layout.py): the real tree passes, and a tree broken
the ways a change could break it fails, naming the file and line at fault."""
import os
import shutil
import subprocess
import sys

import pytest

SOURCE = os.environ.get("VISPROXY_SOURCE_DIR", os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
CHECKER = os.path.join(SOURCE, "cmake", "check_layout.py")


def check(root):
    run = subprocess.run([sys.executable, CHECKER, root], capture_output=True, text=True)
    return run.returncode, run.stdout


def test_the_source_tree_keeps_its_layers():
    code, out = check(SOURCE)
    assert code == 0, out
    assert "0 problems" in out


@pytest.fixture
def tree(tmp_path):
    """A copy of lib/ (sources only) and of one app, to break."""
    root = tmp_path / "src"
    shutil.copytree(os.path.join(SOURCE, "lib"), root / "lib",
                    ignore=shutil.ignore_patterns("*.md", "*.py", "__pycache__"))
    (root / "apps").mkdir()
    (root / "tests").mkdir()
    code, out = check(str(root))
    assert code == 0, out
    return root


def add_include(path, header):
    text = path.read_text()
    path.write_text(f'#include "{header}"\n' + text)


def test_an_include_of_a_higher_layer_fails(tree):
    add_include(tree / "lib/visproxy/mesh/triangle_mesh.h", "visproxy/render/render_job.h")
    code, out = check(str(tree))
    assert code == 1
    assert "lib/visproxy/mesh/triangle_mesh.h:1: lib/visproxy/mesh includes from lib/visproxy/render" in out


def test_a_folder_and_its_subfolder_may_not_depend_on_each_other(tree):
    # render/ is above render/integrators: an integrator may not include the render loop.
    integrators = tree / "lib/visproxy/render/integrators"
    add_include(sorted(integrators.glob("*.cpp"))[0], "visproxy/render/render_job.h")
    code, out = check(str(tree))
    assert code == 1
    assert "lib/visproxy/render/integrators includes from lib/visproxy/render," in out


def test_an_include_that_names_no_file_fails(tree):
    (tree / "apps/tool.cpp").write_text('#include "visproxy/render/renderer_that_moved.h"\nint main() {}\n')
    code, out = check(str(tree))
    assert code == 1
    assert "apps/tool.cpp:1: includes visproxy/render/renderer_that_moved.h, which is no file under lib/" in out


def test_a_folder_outside_the_layers_fails(tree):
    extra = tree / "lib/visproxy/extra"
    extra.mkdir()
    (extra / "thing.cpp").write_text('#include "visproxy/core/errors.h"\n')
    code, out = check(str(tree))
    assert code == 1
    assert "lib/visproxy/extra: not listed in the layers" in out


def test_a_file_over_a_thousand_lines_fails(tree):
    (tree / "lib/visproxy/core/long.cpp").write_text("// line\n" * 1001)
    code, out = check(str(tree))
    assert code == 1
    assert "lib/visproxy/core/long.cpp: 1001 lines" in out
