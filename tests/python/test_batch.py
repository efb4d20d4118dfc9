"""`visproxy batch` on asset lists: shards under GNU parallel, a Dask LocalCluster, a killed
run resumed, a crashed worker and a malformed asset recorded, not fatal.

Run by CTest with the environment of test_visproxy.py. GNU parallel (Debian's `parallel`)
and Dask (`python3-distributed`) are installed by `cmake/bootstrap.sh test`.
"""

import json
import os
import pathlib
import shutil
import signal
import subprocess
import sys
import time

import pytest

import visproxy as vp

CLI = os.environ.get("VISPROXY_CLI", "visproxy")
MESHES = pathlib.Path(os.environ["VISPROXY_MESH_DIR"]).resolve()
SOURCE = pathlib.Path(os.environ["VISPROXY_SOURCE_DIR"])

# Cheap proxies and few rays: the batch machinery, not the figures, is under test.
OPTIONS = ["--proxy", "aabb", "--proxy", "hull", "--proxy", "inside:4", "--rays", "20000", "--timed-rays", "1000",
           "--hausdorff-samples", "1000", "--gssa-lines", "1000", "--seed", "5"]
PY_OPTIONS = dict(proxies=["aabb", "hull", "inside:4"], rays=20000, timed_rays=1000, hausdorff_samples=1000,
                  gssa_lines=1000, seed=5)


def without_timings(summary):
    """The summary less what measures time, and less where it was written."""
    timed = set(summary["timed_fields"])
    strip = lambda item: {k: v for k, v in item.items() if k not in timed}
    return {"assets": summary["assets"], "ok": summary["ok"], "failed": summary["failed"],
            "claims_failed": summary["claims_failed"], "records": [strip(r) for r in summary["records"]],
            "rows": [strip(r) for r in summary["rows"]]}


@pytest.fixture(scope="module")
def assets(tmp_path_factory):
    folder = tmp_path_factory.mktemp("assets")
    for name in ["knot1.off", "cow.off", "sphere.ply", "elephant-with-holes.off"]:
        shutil.copy(MESHES / name, folder / name)
    # Hand-edited garbage: a face naming a vertex that does not exist.
    (folder / "broken.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
    listing = folder / "list.txt"
    listing.write_text("# test assets\n" + "".join(f"{n}\n" for n in
                       ["knot1.off", "broken.obj", "cow.off", "sphere.ply", "elephant-with-holes.off"]))
    return listing


@pytest.fixture(scope="module")
def unsharded(assets, tmp_path_factory):
    out = tmp_path_factory.mktemp("unsharded")
    result = subprocess.run([CLI, "batch", str(assets), "-o", str(out), *OPTIONS], capture_output=True, text=True)
    return out, result


def test_a_malformed_asset_is_reported_and_the_batch_goes_on(unsharded):
    out, result = unsharded
    assert result.returncode == 1, result.stderr  # an asset failed
    failed = [line for line in result.stdout.splitlines() if "broken.obj" in line and "failed:" in line]
    assert len(failed) == 1, result.stdout
    summary = json.loads((out / "summary.json").read_text())
    assert summary["assets"] == 5 and summary["failed"] == 2 and summary["ok"] == 3  # broken.obj, and the open elephant
    by_asset = {pathlib.Path(r["asset"]).name: r for r in summary["records"]}
    assert by_asset["broken.obj"]["status"] == "failed"
    assert "broken.obj" in by_asset["broken.obj"]["error"]
    for name in ["knot1.off", "cow.off", "sphere.ply"]:
        assert by_asset[name]["status"] == "ok", by_asset[name]
        assert (out / by_asset[name]["folder"] / "report.html").is_file()
    assert not list((out / ".partial").iterdir())
    csv = (out / "summary.csv").read_text().splitlines()
    assert csv[0].startswith("asset,folder,triangles,proxy,kind")
    assert any(",failed," in line and "broken.obj" in line for line in csv)


def test_an_open_mesh_with_an_inside_proxy_fails_naming_the_defect(unsharded):
    out, _ = unsharded
    summary = json.loads((out / "summary.json").read_text())
    record = next(r for r in summary["records"] if r["asset"].endswith("elephant-with-holes.off"))
    assert record["status"] == "failed"
    assert "elephant-with-holes.off" in record["error"] and "boundary edges" in record["error"], record["error"]


def test_gnu_parallel_shards_merge_to_the_unsharded_summary(assets, unsharded, tmp_path):
    parallel = shutil.which("parallel")
    if parallel is None:
        pytest.skip("GNU parallel is not installed (cmake/bootstrap.sh test installs it)")
    out = tmp_path / "sharded"
    command = [parallel, "--will-cite", "--halt", "never", CLI, "batch", str(assets), "-o", str(out), *OPTIONS,
               "--shard", "{}/2", ":::", "0", "1"]
    result = subprocess.run(command, capture_output=True, text=True)
    # parallel exits with the number of shards that failed: shard 0 holds the open elephant,
    # shard 1 broken.obj.
    assert result.returncode == 2, result.stdout + result.stderr
    merged = subprocess.run([CLI, "batch", "--merge", str(out)], capture_output=True, text=True)
    assert merged.returncode == 0, merged.stderr
    reference = json.loads((unsharded[0] / "summary.json").read_text())
    assert without_timings(json.loads((out / "summary.json").read_text())) == without_timings(reference)


def test_a_dask_local_cluster_gives_the_same_summary(assets, unsharded, tmp_path):
    distributed = pytest.importorskip("distributed", reason="python3-distributed (cmake/bootstrap.sh test installs it)")
    sys.path.insert(0, str(SOURCE / "apps" / "dask"))
    import visproxy_dask

    out = tmp_path / "dask"
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    client = distributed.Client(cluster)
    try:
        records, summary = visproxy_dask.run(vp.batch_assets(str(assets)), out, client, **PY_OPTIONS)
    finally:
        client.close()
        cluster.close()
    assert [r["status"] for r in records].count("failed") == 2
    reference = json.loads((unsharded[0] / "summary.json").read_text())
    assert without_timings(summary) == without_timings(reference)


def test_the_dask_entry_point_runs_from_the_command_line(assets, tmp_path):
    pytest.importorskip("distributed", reason="python3-distributed (cmake/bootstrap.sh test installs it)")
    out = tmp_path / "dask-cli"
    result = subprocess.run([sys.executable, str(SOURCE / "apps" / "dask" / "visproxy_dask.py"), str(assets), "-o", str(out),
                             "--workers", "2", "--proxy", "aabb", "--rays", "5000"], capture_output=True, text=True)
    assert result.returncode == 1, result.stderr  # broken.obj
    assert "broken.obj: failed:" in result.stdout
    assert json.loads((out / "summary.json").read_text())["assets"] == 5


def wait_for(condition, seconds=120):
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        if condition():
            return True
        time.sleep(0.05)
    return False


def completed(out):
    return [p for p in out.iterdir() if (p / "asset.json").is_file()] if out.exists() else []


def slow_list(tmp_path):
    listing = tmp_path / "slow.txt"
    listing.write_text("".join(f"{MESHES / n}\n" for n in ["knot1.off", "cow.off", "camel.off", "knot2.off"]))
    return listing


SLOW = ["--proxy", "aabb", "--proxy", "outer:256", "--rays", "20000", "--timed-rays", "1000", "--hausdorff-samples",
        "1000", "--seed", "5"]


def test_a_killed_run_resumes_and_keeps_what_was_finished(tmp_path):
    listing, out = slow_list(tmp_path), tmp_path / "killed"
    run = subprocess.Popen([CLI, "batch", str(listing), "-o", str(out), *SLOW], stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE, start_new_session=True)
    assert wait_for(lambda: len(completed(out)) >= 1), "no asset finished"
    os.killpg(run.pid, signal.SIGKILL)  # the batch and its worker, mid-asset
    run.wait()
    first = completed(out)
    assert 1 <= len(first) < 4
    stamps = {p.name: (p / "manifest.json").stat().st_mtime_ns for p in first}
    # Nothing half-written is in place: every folder there has its record and its report.
    for p in out.iterdir():
        if p.is_dir() and p.name not in (".partial", "logs"):
            assert (p / "asset.json").is_file() and (p / "report.html").is_file(), p
    again = subprocess.run([CLI, "batch", str(listing), "-o", str(out), *SLOW], capture_output=True, text=True)
    assert again.returncode == 0, again.stdout + again.stderr
    assert again.stdout.count("(done before)") == len(first)
    assert len(completed(out)) == 4
    for name, stamp in stamps.items():
        assert (out / name / "manifest.json").stat().st_mtime_ns == stamp, name  # not redone
    summary = json.loads((out / "summary.json").read_text())
    assert summary["ok"] == 4 and summary["failed"] == 0


def test_a_crashed_worker_is_recorded_and_the_batch_goes_on(tmp_path):
    listing, out = slow_list(tmp_path), tmp_path / "crashed"
    run = subprocess.Popen([CLI, "batch", str(listing), "-o", str(out), *SLOW], stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE, text=True)

    def worker():
        found = subprocess.run(["pgrep", "-f", "-P", str(run.pid), "batch --one"], capture_output=True, text=True)
        return found.stdout.split()

    assert wait_for(lambda: bool(worker())), "no worker started"
    os.kill(int(worker()[0]), signal.SIGSEGV)  # as if the first asset crashed its process
    stdout, stderr = run.communicate(timeout=600)
    assert run.returncode == 1, stdout + stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["assets"] == 4 and summary["failed"] == 1 and summary["ok"] == 3
    record = next(r for r in summary["records"] if r["status"] == "failed")
    assert "signal 11" in record["error"] and record["asset"] in record["error"], record["error"]
    # The crashed asset's work stays in .partial; in place are only the three finished folders.
    in_place = [p for p in out.iterdir() if p.is_dir() and p.name not in (".partial", "logs")]
    assert sorted(p.name for p in in_place) == sorted(r["folder"] for r in summary["records"] if r["status"] == "ok")
    assert all((p / "asset.json").is_file() for p in in_place)
