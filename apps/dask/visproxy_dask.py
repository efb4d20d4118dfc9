#!/usr/bin/env python3
"""visproxy batch over a Dask distributed cluster.

Maps the assets of a batch list over the cluster's workers, one `visproxy.batch_asset`
task per asset, each writing its proxy folder (or its failure record) into the shared
batch folder, then writes the summary with `visproxy.batch_merge`. The folder layout,
resuming and failure records are those of `visproxy batch`, so runs of either kind can
fill the same folder and be merged together.

    visproxy-dask LIST -o DIR [--scheduler ADDRESS | --workers N] [--proxy SPEC]... [--seed S] [--rays N]

Without --scheduler a LocalCluster of N worker processes (one thread each) runs on this
machine. Every worker must be able to import the `visproxy` module and to read the meshes
and DIR at the same paths (a shared file system).
"""

import argparse
import sys

import visproxy


def process(mesh, output, **options):
    """One asset on a worker (the module's functions are not picklable; this one is)."""
    import visproxy as worker_visproxy

    return worker_visproxy.batch_asset(mesh, output, **options)


def run(assets, output, client, proxies=None, seed=1, rays=200000, timed_rays=50000, hausdorff_samples=20000,
        gssa_lines=100000, retry_failed=False):
    """Processes `assets` (paths) into the batch folder `output` on the Dask `client`.

    Returns (records, summary): each asset's record in the order of `assets`, and the
    summary batch_merge wrote over every record in `output`.
    """
    options = dict(proxies=proxies, seed=seed, rays=rays, timed_rays=timed_rays, hausdorff_samples=hausdorff_samples,
                   gssa_lines=gssa_lines, retry_failed=retry_failed)
    try:  # `process` travels by value, so workers need only the visproxy module, not this file
        import cloudpickle

        cloudpickle.register_pickle_by_value(sys.modules[__name__])
    except (ImportError, AttributeError, ValueError):
        pass
    # pure=False: an asset's task runs even if an equal one ran before (the folder decides).
    futures = client.map(process, [str(a) for a in assets], output=str(output), pure=False, **options)
    records = client.gather(futures)
    return records, visproxy.batch_merge(str(output))


def main(argv=None):
    parser = argparse.ArgumentParser(prog="visproxy-dask", description=__doc__.split("\n\n")[1])
    parser.add_argument("list", help="text file of mesh paths (one per line, relative to the file) or a folder")
    parser.add_argument("-o", "--output", required=True, help="batch folder (created if missing)")
    parser.add_argument("--scheduler", help="address of a running Dask scheduler (tcp://host:8786)")
    parser.add_argument("--workers", type=int, default=2, help="LocalCluster worker processes without --scheduler [2]")
    parser.add_argument("--proxy", action="append", help="proxy spec (repeatable); default: visproxy build's set")
    parser.add_argument("--seed", type=int, default=1, help="seed of every random choice [1]")
    parser.add_argument("--rays", type=int, default=200000, help="isotropic lines per asset for measure [200000]")
    parser.add_argument("--retry-failed", action="store_true", help="process assets again whose failure is recorded")
    args = parser.parse_args(argv)
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        print("visproxy-dask: the 'distributed' module is missing (Debian: apt install python3-distributed)",
              file=sys.stderr)
        return 2
    try:
        assets = visproxy.batch_assets(args.list)
    except (visproxy.Error, OSError, ValueError) as error:
        print(f"visproxy-dask: {error}", file=sys.stderr)
        return 2
    cluster = None
    if args.scheduler:
        client = Client(args.scheduler)
    else:
        cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True, dashboard_address=None)
        client = Client(cluster)
    try:
        records, summary = run(assets, args.output, client, proxies=args.proxy, seed=args.seed, rays=args.rays,
                               retry_failed=args.retry_failed)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    for record in records:
        state = record["status"] if record["status"] != "failed" else "failed: " + str(record["error"])
        print(f"visproxy-dask: {record['asset']}: {state}")
    not_ok = sum(1 for record in records if record["status"] != "ok")
    print(f"visproxy-dask: {len(records)} assets, {not_ok} not ok; summary of all {summary['assets']} assets in "
          f"{args.output}/summary.json, summary.csv, summary.html")
    return 0 if not_ok == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
