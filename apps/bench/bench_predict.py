#!/usr/bin/env python3
"""visproxy-bench-predict: are the report's predictions true on the render?

For each scene (one proxied mesh, possibly instanced many times), R times over:
  1. `visproxy measure MESH DIR --scene SCENE` and `visproxy report DIR`: the predicted
     efficiency of each use over the whole render (recommendation.json's render_efficiency
     and render_interval: the shadow ray's prediction carried to the render by the share of
     a sample's time the mesh's shadow tests take);
  2. `visproxy compare SCENE --equal samples --rounds 16` with the three modes below: the
     measured efficiency (1 / (MSE x time)) of each mode over exact's. The modes take turns
     and render the same passes in each, so that their images share their samples (the
     MSE ratio is then the estimators' own) and each turn's time is weighed against
     exact's in the same round (the median round's ratio, which the machine's pauses do
     not move).
It prints, per scene and use, the predictions (median, and the widest interval over the
runs) against the measured ratios (median and range over the runs), whether every
measured ratio lies inside the predicted interval and within 25 % of the prediction, and
the report's advice in each run (the proxy it ships, or trace the mesh).

Uses and the modes that realise them:
  bounds           <-> "bounds" (the first outside proxy the instance names; scenes whose
                       instances also name an inside proxy are predicted for the outside one only)
  eq. 8            <-> "<first spec> eq8 optimal" (the scene's optimal probabilities, which the
                       prediction assumes)
  control variate  <-> "<first spec> control variate learned" (its probabilities learned per pixel,
                       as near as the renderer gets to the optimum the prediction assumes)

Usage: visproxy-bench-predict [--repetitions R] [--seconds S] [--rounds K] [--rays N] [--reference-spp K]
                              [--work DIR] [SCENE...]
Without SCENE: the four prediction scenes in data/scenes (camel-herd, cow-field,
knot-lanterns, far-armadillo).
"""

import argparse
import csv
import json
import os
import statistics
import subprocess
import sys
import tempfile

DEFAULT_SCENES = ["camel-herd.json", "cow-field.json", "knot-lanterns.json", "far-armadillo.json"]
USES = [("bounds", "bounds"), ("eq8", "eq8 optimal"), ("control_variate", "control variate learned")]


def run(command, log):
    result = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    log.write("$ " + " ".join(command) + "\n" + result.stdout + "\n")
    if result.returncode != 0:
        sys.exit("visproxy-bench-predict: failed (exit %d): %s\n%s" % (result.returncode, " ".join(command), result.stdout[-2000:]))
    return result.stdout


def proxied_mesh(scene_path, mesh_dir):
    """The one mesh of the scene whose instances name proxies: (file, specs), or (None, why)."""
    scene = json.load(open(scene_path))
    names = {i["mesh"] for i in scene["instances"] if i.get("proxies")}
    if len(names) != 1:
        return None, "%d proxied meshes (the bench needs one)" % len(names)
    name = names.pop()
    mesh = scene["meshes"][name]
    if "file" not in mesh or "subdivide" in mesh:
        return None, "its proxied mesh is not a plain file"
    file = mesh["file"]
    if file.startswith("cgal-demo:"):
        file = os.path.join(mesh_dir, file[len("cgal-demo:"):])
    elif not os.path.isabs(file):
        file = os.path.join(os.path.dirname(scene_path), file)
    specs = next(i["proxies"] for i in scene["instances"] if i["mesh"] == name)
    return (file, specs), None


def proxy_name(spec):
    return spec.replace(":", "-").replace(",", "-").replace("=", "")


def spread(values):
    return "%.2f (%.2f-%.2f)" % (statistics.median(values), min(values), max(values))


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--visproxy", default=os.environ.get("VISPROXY_CLI", "visproxy"))
    parser.add_argument("--mesh-dir", default=os.environ.get("VISPROXY_MESH_DIR", ""))
    parser.add_argument("--scene-dir", default=os.environ.get("VISPROXY_SCENE_DIR", os.path.join(here, "..", "..", "data", "scenes")))
    parser.add_argument("--repetitions", type=int, default=3)
    parser.add_argument("--seconds", type=float, default=4.0, help="time per mode of each compare run")
    parser.add_argument("--rounds", type=int, default=16, help="turns of each compare run")
    parser.add_argument("--rays", type=int, default=200000, help="shadow segments of each measure run")
    # The reference's own noise adds to every mode's MSE: compare subtracts it, and a
    # reference far less noisy than a 4-second render (about 1000 spp here) keeps that
    # correction small.
    parser.add_argument("--reference-spp", type=int, default=16384)
    parser.add_argument("--work", default="")
    parser.add_argument("scenes", nargs="*")
    args = parser.parse_args()
    scenes = args.scenes or [os.path.join(args.scene_dir, s) for s in DEFAULT_SCENES]
    work = args.work or tempfile.mkdtemp(prefix="visproxy-bench-predict-")
    os.makedirs(work, exist_ok=True)
    log = open(os.path.join(work, "log.txt"), "w")
    cache = os.path.join(work, "cache")
    rows = []
    for scene in scenes:
        label = os.path.splitext(os.path.basename(scene))[0]
        found, why = proxied_mesh(scene, args.mesh_dir)
        if not found:
            print("%s: skipped, %s" % (label, why), file=sys.stderr)
            continue
        mesh, specs = found
        folder = os.path.join(work, label, "proxies")
        print("%s: building %s of %s ..." % (label, ", ".join(specs), os.path.basename(mesh)), file=sys.stderr)
        run([args.visproxy, "build", mesh, "-o", folder, "--progress", "never"] + sum([["--proxy", s] for s in specs], []), log)
        run([args.visproxy, "verify", mesh, folder], log)
        first = specs[0]
        outside = next((s for s in specs if s.split(":")[0] in ("aabb", "obb", "hull", "wrap", "outer")), None)
        predicted = {use: [] for use, _ in USES}
        advice = {use: [] for use, _ in USES}
        measured = {use: [] for use, _ in USES}
        share = []
        reference = os.path.join(work, label, "reference.pfm")
        for r in range(1, args.repetitions + 1):
            print("%s: run %d of %d ..." % (label, r, args.repetitions), file=sys.stderr)
            run([args.visproxy, "measure", mesh, folder, "--scene", scene, "--rays", str(args.rays), "--seed", str(r),
                 "--progress", "never"], log)
            run([args.visproxy, "report", folder, "--no-pictures"], log)
            recommendation = json.load(open(os.path.join(folder, "recommendation.json")))
            share.append(recommendation["render_share"]["share"])
            by_name = {p["name"]: p for p in recommendation["proxies"]}
            for use, _ in USES:
                chosen = recommendation["uses"].get(use, {})
                advice[use].append(chosen.get("proxy") if chosen.get("beats_mesh") else "trace the mesh")
            for use, _ in USES:
                spec = outside if use == "bounds" else first
                figures = by_name.get(proxy_name(spec), {}).get(use, {}) if spec else {}
                if figures.get("usable") and figures.get("render_efficiency") is not None:
                    predicted[use].append((figures["render_efficiency"], figures["render_interval"], figures["efficiency"]))
            out = os.path.join(work, label, "compare-%d" % r)
            command = [args.visproxy, "compare", scene, "-o", out, "--seconds", str(args.seconds), "--seed", str(r),
                       "--no-count", "--convergence-points", "1", "--proxy", first, "--cache", cache,
                       "--equal", "samples", "--rounds", str(args.rounds)] + sum([["--mode", m] for _, m in USES], [])
            command += ["--reference", reference] if os.path.exists(reference) else ["--reference-spp", str(args.reference_spp)]
            run(command, log)
            if not os.path.exists(reference):
                # With its noise (reference.noise.json), which compare subtracts from every MSE.
                os.replace(os.path.join(out, "reference.noise.json"), os.path.splitext(reference)[0] + ".noise.json")
                os.replace(os.path.join(out, "reference.pfm"), reference)
            with open(os.path.join(out, "table.csv")) as table:
                modes = {row["mode"]: row for row in csv.DictReader(table)}
            for use, mode in USES:
                name = mode if use == "bounds" else first + " " + mode
                if name in modes:
                    measured[use].append(float(modes[name]["efficiency_over_exact"]))
        for use, _ in USES:
            spec = outside if use == "bounds" else first
            rows.append((label, use, spec or "-", share, predicted[use], measured[use], advice[use]))

    print("\nPredicted against measured efficiency over exact, whole render, %d runs each (measure --scene + report, "
          "then compare at equal samples, exact's pace for %.1f s per mode).\nshare: the mesh's shadow tests' share of a sample's time; ray: the "
          "shadow ray's predicted efficiency; render: the render's, median with the widest interval over the runs; "
          "measured: compare's efficiency over exact, median and range; inside: every measured ratio in the "
          "predicted interval; 25 %%: every one within 25 %% of the median prediction.\n" % (args.repetitions, args.seconds))
    print("%-15s %-16s %-12s %-18s %-18s %-30s %-18s %-6s %-5s" % ("scene", "use", "proxy", "share", "ray", "render [interval]",
                                                                 "measured", "inside", "25 %"))
    inside_count = within_count = total = 0
    for label, use, spec, share, predicted, measured, advised in rows:
        if not predicted or not measured:
            print("%-15s %-16s %-12s %s" % (label, use, spec, "not usable or not rendered (see log.txt)"))
            continue
        point = statistics.median(p[0] for p in predicted)
        low = min(p[1][0] for p in predicted)
        high = max(p[1][1] for p in predicted)
        inside = all(low <= m <= high for m in measured)
        within = all(abs(m - point) <= 0.25 * point for m in measured)
        total += 1
        inside_count += inside
        within_count += within
        print("%-15s %-16s %-12s %-18s %-18s %-30s %-18s %-6s %-5s" % (
            label, use, spec, spread([100 * s for s in share]) + " %", spread([p[2] for p in predicted]),
            "%.2f [%.2f, %.2f]" % (point, low, high), spread(measured), "yes" if inside else "no",
            "yes" if within else "no"))
        if advised:
            names = sorted(set(advised), key=advised.index)
            print("%-15s %-16s report's advice over the runs: %s" % (
                "", "", ", ".join("%s x%d" % (n, advised.count(n)) for n in names)))
    print("\n%d of %d (scene, use) pairs inside their interval, %d within 25 %%. Work folder: %s" % (
        inside_count, total, within_count, work))


if __name__ == "__main__":
    main()
