#!/usr/bin/env python3
"""Benchmark harness: runs quadify over a folder of meshes, one mesh per process, with a time and
memory limit per mesh, and writes one table (Markdown, TSV, JSON) of per-mesh figures.

  bench/run_bench.py                         # info over ../shared/meshes
  bench/run_bench.py --mode param            # seamless parametrization + check of the written OBJ
  bench/run_bench.py --mode remesh --target-faces 5000
  bench/run_bench.py --meshes DIR --only spot,knot1 --timeout 300 --mem-gb 8
  bench/run_bench.py --mode remesh --max-faces 0   # also the large meshes (hours)
  bench/run_bench.py --mode remesh --capture-breakdown  # + the capture's missed length by cause

In param and remesh modes, meshes with more than --max-faces triangles (40,000; from the folder's
MANIFEST.tsv, or counted in an OBJ) are listed as skipped, not run: over ../shared/meshes that
leaves the large scans (armadillo, crank, dilo, dragon, feline, mask, shark_b) to an explicit run.

Every figure comes from the JSON reports that quadify writes (--json), and for param/remesh from
`quadify check` run on the written file, so the table measures what a user gets.
Standard library only.
"""
import argparse
import json
import os
import resource
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(Path(__file__).resolve().parent))
import capture_breakdown  # noqa: E402  (bench/capture_breakdown.py)
MESH_EXT = {".obj", ".off", ".ply", ".stl", ".gltf", ".glb"}


def run_limited(cmd, timeout_s, mem_bytes):
    """Runs cmd with an address-space limit and a wall-clock limit. Returns a dict with exit code
    (or signal), seconds, peak RSS (MB) of that process alone, and the tail of stderr."""
    def limit():
        if mem_bytes:
            resource.setrlimit(resource.RLIMIT_AS, (mem_bytes, mem_bytes))
        os.setsid()

    start = time.monotonic()
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, preexec_fn=limit)
    timed_out = threading.Event()

    def kill():
        timed_out.set()
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass

    timer = threading.Timer(timeout_s, kill)
    timer.start()
    stderr_chunks = []
    reader = threading.Thread(target=lambda: stderr_chunks.append(proc.stderr.read()))
    reader.start()
    _, status, usage = os.wait4(proc.pid, 0)
    timer.cancel()
    reader.join()
    proc.returncode = os.waitstatus_to_exitcode(status)
    seconds = time.monotonic() - start
    stderr = b"".join(stderr_chunks).decode("utf-8", "replace").strip().splitlines()
    if timed_out.is_set():
        state = "timeout"
    elif proc.returncode < 0:
        state = "signal %d" % -proc.returncode
    elif proc.returncode == 0:
        state = "ok"
    elif proc.returncode == 2:
        state = "bad input"
    else:
        state = "failed (%d)" % proc.returncode
    return {
        "status": state,
        "exit": proc.returncode,
        "seconds": round(seconds, 2),
        "peak_mb": round(usage.ru_maxrss / 1024.0, 1),
        "message": stderr[-1] if stderr and proc.returncode != 0 else "",
    }


def load_json(path):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return {}


def dig(obj, dotted):
    for key in dotted.split("."):
        if not isinstance(obj, dict) or key not in obj:
            return None
        obj = obj[key]
    return obj


# Columns of each mode: (header, report, dotted path). "run" = the stage's report, "check" =
# `quadify check` on its output.
COLUMNS = {
    "info": [
        ("V", "run", "input.vertices"), ("F", "run", "input.faces"),
        ("welded", "run", "repair.welded_vertices"), ("degenerate", "run", "repair.degenerate_faces_removed"),
        ("dup faces", "run", "repair.duplicate_faces_removed"),
        ("unref V", "run", "repair.unreferenced_vertices_removed"),
        ("nm edges split", "run", "repair.nonmanifold_edges_split"),
        ("nm verts split", "run", "repair.nonmanifold_vertices_split"),
        ("reoriented", "run", "repair.faces_reoriented"),
        ("components", "run", "mesh.components"), ("boundary loops", "run", "mesh.boundary_loops"),
        ("genus", "run", "mesh.genus"),
    ],
    "param": [
        ("F", "run", "mesh.faces"), ("tau", "check", "check.tau"), ("flips", "check", "check.flipped"),
        ("cones", "check", "check.cones"), ("seam residual", "check", "check.seam_residual_abs"),
        ("integer matchings", "check", "check.matchings_integer"),
        ("GB error", "check", "check.gauss_bonnet_error"),
        ("patches", "run", "param.patches"), ("improved", "run", "param.improved"),
        ("s param", "run", "timings.param"),
    ],
    "remesh": [
        ("F in", "run", "mesh.faces"), ("quads", "check", "check.faces"),
        ("non-quads", "check", "check.non_quads"), ("irregular", "check", "check.irregular_vertices"),
        ("flipped", "check", "check.flipped_quads"), ("sj min", "check", "check.sj_min"),
        ("manifold", "check", "check.manifold"), ("Hausdorff", "check", "check.hausdorff_sym"),
        ("feature capture", "check", "check.feature_capture"),
        ("components", "check", "check.components"), ("genus", "check", "check.genus"),
        ("boundary loops", "check", "check.boundary_loops"), ("cones", "run", "param.cones"),
        ("cancelled pairs", "run", "param.cancelled_pairs"), ("tau", "run", "param.tau"),
        ("scale restarts", "run", "quantize.scale_retries"), ("s param", "run", "timings.param"),
        ("s quantize", "run", "timings.quantize"), ("s extract", "run", "timings.extract"),
    ],
}


def fmt(x):
    if x is None:
        return "–"
    if isinstance(x, bool):
        return "yes" if x else "no"
    if isinstance(x, float):
        if x == 0:
            return "0"
        return "%.3g" % x if abs(x) < 1e-2 or abs(x) >= 1e4 else "%.4g" % x
    return str(x)


def manifest_face_counts(meshes_dir):
    """File name -> triangle count from the folder's MANIFEST.tsv (n_faces column), if any."""
    counts = {}
    manifest = meshes_dir / "MANIFEST.tsv"
    if not manifest.is_file():
        return counts
    lines = manifest.read_text(errors="replace").splitlines()
    if not lines:
        return counts
    header = lines[0].split("\t")
    if "n_faces" not in header:
        return counts
    col = header.index("n_faces")
    for line in lines[1:]:
        cells = line.split("\t")
        if len(cells) > col and cells[col].strip().isdigit():
            counts[cells[0]] = int(cells[col])
    return counts


def count_obj_faces(path):
    """Number of `f` lines of an OBJ (polygons, not triangles; a cheap size estimate)."""
    n = 0
    with open(path, "rb") as f:
        for line in f:
            if line.startswith(b"f "):
                n += 1
    return n


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--meshes", default=str(REPO.parent / "shared" / "meshes"), help="folder of input meshes")
    ap.add_argument("--quadify", default=str(REPO / "build" / "bin" / "quadify"), help="the quadify binary")
    ap.add_argument("--mode", choices=sorted(COLUMNS), default="info")
    ap.add_argument("--out", default=None, help="output folder (default bench/results/<mode>)")
    ap.add_argument("--only", default="", help="comma-separated mesh names (file stems) to run")
    ap.add_argument("--timeout", type=float, default=600, help="seconds per mesh and stage")
    ap.add_argument("--mem-gb", type=float, default=12, help="address-space limit per process (GiB)")
    ap.add_argument("--target-faces", type=int, default=5000, help="remesh mode: target quad count")
    ap.add_argument("--extra", default="", help="extra arguments passed to the stage command")
    ap.add_argument("--capture-breakdown", action="store_true",
                    help="remesh mode: also write each integer map (outputs/<mesh>_map.obj) and split the "
                         "feature capture's missed length by cause (bench/capture_breakdown.py)")
    ap.add_argument("--max-faces", type=int, default=40000,
                    help="param/remesh: skip meshes with more triangles than this (0 = run all; "
                         "ignored for meshes named in --only)")
    args = ap.parse_args()

    meshes_dir = Path(args.meshes)
    if not meshes_dir.is_dir():
        sys.exit("run_bench: no mesh folder %s (pass --meshes)" % meshes_dir)
    quadify = Path(args.quadify)
    if not quadify.is_file():
        sys.exit("run_bench: %s not found; build first (scripts/quickstart.sh demo)" % quadify)
    out_dir = Path(args.out) if args.out else REPO / "bench" / "results" / args.mode
    (out_dir / "reports").mkdir(parents=True, exist_ok=True)
    (out_dir / "outputs").mkdir(parents=True, exist_ok=True)
    only = {s for s in args.only.split(",") if s}
    files = sorted(p for p in meshes_dir.iterdir() if p.suffix.lower() in MESH_EXT and (not only or p.stem in only))
    mem = int(args.mem_gb * (1 << 30))
    face_counts = manifest_face_counts(meshes_dir)
    extra = args.extra.split() if args.extra else []

    # Feature capture's missed length by cause (shares of the sharp-edge length).
    breakdown_columns = []
    if args.capture_breakdown and args.mode == "remesh":
        breakdown_columns = [("missed unaligned", "unaligned"), ("missed parallel", "parallel"),
                             ("missed chain end", "chain end"), ("missed chord", "chord"),
                             ("missed other", "other")]
    rows = []
    for path in files:
        name = path.stem
        n_faces = face_counts.get(path.name)
        if n_faces is None and path.suffix.lower() == ".obj":
            n_faces = count_obj_faces(path)
        if (args.mode != "info" and args.max_faces > 0 and name not in only and n_faces is not None
                and n_faces > args.max_faces):
            message = "%d triangles > --max-faces %d" % (n_faces, args.max_faces)
            rows.append({"mesh": name, "status": "skipped", "seconds": 0.0, "peak_mb": 0.0, "message": message})
            print("%-28s %-10s %s" % (name, "skipped", message), file=sys.stderr, flush=True)
            continue
        run_json = out_dir / "reports" / (name + ".json")
        check_json = out_dir / "reports" / (name + ".check.json")
        for stale in (run_json, check_json):
            stale.unlink(missing_ok=True)
        if args.mode == "info":
            cmd = [str(quadify), "info", str(path), "--json", str(run_json), "-q"] + extra
            output = None
        elif args.mode == "param":
            output = out_dir / "outputs" / (name + "_uv.obj")
            cmd = [str(quadify), "param", str(path), "-o", str(output), "--json", str(run_json), "-q"] + extra
        else:
            output = out_dir / "outputs" / (name + "_quad.obj")
            cmd = [str(quadify), str(path), "-o", str(output), "--target-faces", str(args.target_faces),
                   "--json", str(run_json), "-q"] + extra
            map_output = out_dir / "outputs" / (name + "_map.obj")
            if args.capture_breakdown:
                map_output.unlink(missing_ok=True)
                cmd += ["--map", str(map_output)]
        if output is not None:
            output.unlink(missing_ok=True)
        result = run_limited(cmd, args.timeout, mem)
        check = {}
        if output is not None and result["exit"] == 0:
            ccmd = [str(quadify), "check", str(output), "--json", str(check_json), "-q"]
            if args.mode == "remesh":
                ccmd += ["--reference", str(path)]
            cres = run_limited(ccmd, args.timeout, mem)
            if cres["exit"] != 0:
                result["status"] = "check " + cres["status"]
                result["message"] = cres["message"]
            check = load_json(check_json)
        reports = {"run": load_json(run_json), "check": check}
        row = {"mesh": name, **result}
        for header, which, dotted in COLUMNS[args.mode]:
            row[header] = dig(reports[which], dotted)
        if breakdown_columns and dig(check, "check.feature_capture") not in (None, -1) and map_output.is_file():
            try:
                missed = capture_breakdown.breakdown(str(map_output), str(output))["missed"]
                for header, cause in breakdown_columns:
                    row[header] = missed[cause]
            except (OSError, ValueError, IndexError) as e:
                row["message"] = (row.get("message") or "") + " capture breakdown: %s" % e
        rows.append(row)
        print("%-28s %-10s %7.2fs %7.1f MB %s" % (name, result["status"], result["seconds"], result["peak_mb"],
                                                   result["message"]), file=sys.stderr, flush=True)

    headers = (["mesh", "status", "seconds", "peak_mb"] + [h for h, _, _ in COLUMNS[args.mode]] +
               [h for h, _ in breakdown_columns] + ["message"])
    with open(out_dir / "table.tsv", "w") as f:
        f.write("\t".join(headers) + "\n")
        for r in rows:
            f.write("\t".join(fmt(r.get(h)) for h in headers) + "\n")
    with open(out_dir / "table.json", "w") as f:
        json.dump({"mode": args.mode, "meshes": str(meshes_dir), "rows": rows}, f, indent=1)
    with open(out_dir / "table.md", "w") as f:
        f.write("| " + " | ".join(headers) + " |\n")
        f.write("|" + "---|" * len(headers) + "\n")
        for r in rows:
            f.write("| " + " | ".join(fmt(r.get(h)).replace("|", "\\|") for h in headers) + " |\n")
    print("run_bench: %d meshes, table in %s" % (len(rows), out_dir / "table.md"), file=sys.stderr)
    bad = [r["mesh"] for r in rows if r["status"] not in ("ok", "bad input", "skipped")]
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
