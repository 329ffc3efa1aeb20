# SPDX-License-Identifier: GPL-3.0-or-later
"""Unwrap mesh files headlessly with uvflat and write the results and UV layout PNGs.

    .venv/bin/python blender_scripts/unwrap.py INPUT OUTPUT [--method lscm] [options]
    .venv/bin/python blender_scripts/unwrap.py INPUT... OUTPUT_FOLDER [--jobs N] [--format glb]

INPUT: .obj, .ply, .off or .blend; every mesh object of the file is unwrapped.  OUTPUT: .obj,
.glb or .blend, with the new UV map; the UV layout is drawn to OUTPUT's name with ``_uv.png``
(or ``--png``).  Several inputs, a folder or a glob pattern make a batch: every file is
unwrapped by its own worker process (``--jobs``, default: the number of cores) into
OUTPUT_FOLDER/<name>.<format>, with one summary line per file and a final table; the exit
status is non-zero if any file failed.  ``--report report.json`` writes every chart report.
Goes through the add-on's own operator (``bpy.ops.uv.uvflat_unwrap``), registered from
``addon/``.

A batch runs on an existing Dask cluster with ``--cluster ADDRESS`` instead of ``--jobs``:

    .venv/bin/python -m pip install 'dask[distributed]'
    .venv/bin/python blender_scripts/unwrap.py INPUT... OUTPUT_FOLDER --cluster tcp://HOST:8786

One task per file, each running the very same per-file process as ``--jobs`` on a worker, so the
outputs, the per-file lines, the table and ``--report`` are the same.  A task whose worker dies
is run again on another worker (a task that raises, up to twice: Dask ``retries=``); each file is
written under a hidden name and renamed into place when complete, so a file is never left half
written.  The workers need this environment (``bpy``, ``uvflat``) and must see this script, the
inputs and OUTPUT_FOLDER under the same paths (a shared file system).  Why Dask: it is pure
Python and installs with pip, lighter than Ray, with no separate runtime beside the workers, and
a cluster is just a TCP scheduler address such as tcp://host:8786 (``dask scheduler`` on one
machine, ``dask worker tcp://host:8786`` on each of the others).

Input the importers would repair silently is refused with one line naming the file and the
element (a non-finite vertex, a face naming a missing vertex, an empty or truncated file, a file
with no faces), except a face naming a vertex more than once, which is repaired and reported
(``repairs`` in ``--report``): the repeated corners of a face are merged (``f 1 2 2 3 4``
becomes ``f 1 2 3 4``), and a face left with fewer than three corners or still naming a vertex
twice (``f 1 2 1 3``) is removed.
"""

from __future__ import annotations

import argparse
import functools
import glob
import json
import math
import os
import sys
import time
import uuid
from concurrent.futures import ThreadPoolExecutor, as_completed
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import bpy  # noqa: E402
import numpy as np  # noqa: E402

import cluster  # noqa: E402
import common  # noqa: E402


def log(message, t0=[time.perf_counter()]):  # noqa: B006 - start time of the run
    print(f"[{time.perf_counter() - t0[0]:7.2f} s] {message}", flush=True)


INPUT_SUFFIXES = (".obj", ".ply", ".off", ".blend")
OUTPUT_SUFFIXES = (".obj", ".glb", ".blend")
MAX_LAYOUT_SIZE = 16384


class UsageError(Exception):
    """A bad command-line argument: reported as one line, exit status 1, nothing written."""


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line and status 1 instead of argparse's usage + status 2
        raise UsageError(message)


# Declared automatic-seams options whose flags are written by hand: avoid_vertices comes from
# a vertex group (--avoid-group), sharp_angle is given in degrees (--sharp-angle).
_AUTO_SEAM_FLAGS_BY_HAND = ("avoid_vertices", "sharp_angle")


_METAVARS = {"max_stretch": "S", "max_cones": "N", "visibility_weight": "W"}


def auto_seam_specs():
    """The core's declared automatic-seams options (``uvflat.AUTO_SEAM_OPTIONS``) by name."""
    import uvflat

    return {s["name"]: s for s in uvflat.AUTO_SEAM_OPTIONS}


def auto_seam_flag(name: str) -> str:
    return "--" + name.replace("_", "-")


def _add_auto_seam_flags(parser):
    """A flag for every declared automatic-seams option but those written by hand, with the
    core's default and choices (``--auto-seams``, ``--max-stretch``, ``--max-cones``,
    ``--visibility-weight``, ``--symmetry``)."""
    for name, spec in auto_seam_specs().items():
        if name in _AUTO_SEAM_FLAGS_BY_HAND:
            continue
        # (argparse %-formats help texts)
        flag, doc = auto_seam_flag(name), "automatic seams: " + spec["doc"].replace("%", "%%")
        if spec["type"] == "bool":
            parser.add_argument(flag, action=argparse.BooleanOptionalAction,
                                default=spec["default"], help=doc)
        elif spec["type"] == "choice":
            parser.add_argument(flag, choices=spec["choices"], default=spec["default"], help=doc)
        elif spec["type"] in ("int", "float"):
            parser.add_argument(flag, type=int if spec["type"] == "int" else float,
                                default=spec["default"], metavar=_METAVARS.get(name), help=doc)
        else:  # a new kind of option needs its flag written by hand
            raise RuntimeError(f"automatic-seams option {name} of type {spec['type']} has no flag")


def _check_declared(flag: str, value, spec) -> None:
    """Raise UsageError when ``value`` is outside the declared option's domain."""
    if spec["type"] == "float" and not math.isfinite(value):
        raise UsageError(f"{flag} {value}: must be a finite number")
    low, high = spec["min"], spec["max"]
    if (low is not None and (value < low or value == low and spec["min_exclusive"])
            or high is not None and (value > high or value == high and spec["max_exclusive"])):
        bounds = [f"{'greater than' if spec['min_exclusive'] else 'at least'} {low:g}"
                  if low is not None else "",
                  f"{'less than' if spec['max_exclusive'] else 'at most'} {high:g}"
                  if high is not None else ""]
        raise UsageError(f"{flag} {value}: out of range (must be "
                         f"{' and '.join(b for b in bounds if b)})")


def parse_args(argv):
    """Parsed arguments; ``args.batch`` tells a batch (several inputs, a folder or a glob)
    from a single file, whose ``args.inputs`` are then the expanded input files."""
    parser = _Parser(
        description="Unwrap a mesh file headlessly with uvflat.",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("paths", nargs="+", metavar="INPUT... OUTPUT",
                        help=f"input files ({', '.join(INPUT_SUFFIXES)}), folders or glob "
                             f"patterns, then the output file ({', '.join(OUTPUT_SUFFIXES)}) or, "
                             "for several inputs, the output folder")
    parser.add_argument("--method", default="abf",
                        help="uvflat method (tutte, harmonic, mean_value, lscm, spectral, bff, ...)")
    parser.add_argument("--boundary", choices=("circle", "square", "virtual", "free", "convex"),
                        default=None,
                        help="tutte/harmonic/mean_value: circle, square or virtual (default "
                             "circle); abf: free or convex (default free)")
    parser.add_argument("--solver", choices=("abf++", "abf"), default=None,
                        help="abf: ABF++ block elimination or the plain ABF system (default abf++)")
    parser.add_argument("--max-iterations", type=int, default=None,
                        help="iterative methods: most iterations (default: the method's)")
    parser.add_argument("--tolerance-exponent", type=int, default=None,
                        help="iterative methods: tolerance as a power of ten (default: the "
                             "method's)")
    parser.add_argument("--seams-from-islands", action="store_true",
                        help="mark seams from the islands of the input's active UV map first")
    parser.add_argument("--pack", choices=("around", "all", "off"), default=None,
                        help="around: pack the new islands around the other islands of the UV "
                             "map; all: over the whole tile; off: fit them to the previous UVs "
                             "(default around)")
    parser.add_argument("--no-pack", action="store_true", help="same as --pack off")
    parser.add_argument("--texel-density", type=float, default=None, metavar="PX_PER_M",
                        help="texture pixels per metre of surface of the new islands, on a "
                             "texture of --texture-size pixels (packed without scaling: islands "
                             "may not fit in the tile); default: as the packing does it")
    parser.add_argument("--texture-size", type=int, default=None, metavar="PX",
                        help="texture size in pixels of --texel-density (default 1024) and of "
                             "the per-island densities of --report")
    parser.add_argument("--margin", type=float, default=0.001, help="packing margin")
    parser.add_argument("--margin-method", choices=("scaled", "add", "fraction"),
                        default="scaled", help="packing margin method")
    parser.add_argument("--shape-method", choices=("concave", "convex", "aabb"),
                        default="concave", help="island shape used by the packer")
    parser.add_argument("--no-rotate", action="store_true", help="do not rotate islands to pack")
    parser.add_argument("--no-correct-aspect", action="store_true",
                        help="ignore the aspect ratio of the active material's image texture")
    parser.add_argument("--uv-name", default=None,
                        help="write into a new UV map of this name (default: the active one); "
                             "it becomes the active and the render UV map")
    _add_auto_seam_flags(parser)
    parser.add_argument("--sharp-angle", type=float, default=None,
                        help="automatic seams: prefer edges whose dihedral angle is at least "
                             "this many degrees")
    parser.add_argument("--avoid-group", default="",
                        help="automatic seams: vertex group (in a .blend input) where new "
                             "seams must not go")
    parser.add_argument("--mark-seams", action=argparse.BooleanOptionalAction, default=True,
                        help="mark the cuts automatic seams made as edge seams in the output")
    parser.add_argument("--seams-only", action="store_true",
                        help="mark the seams automatic seams would cut and write no UVs "
                             "(Mark Seams Only): review and edit them in the .blend, then "
                             "unwrap; needs .blend output")
    parser.add_argument("--png", type=Path, default=None, help="UV layout image path")
    parser.add_argument("--size", type=int, default=1024, help="UV layout image size")
    parser.add_argument("--report", type=Path, default=None,
                        help="write every chart report (per file and object) to this JSON file")
    parser.add_argument("--jobs", type=int, default=None,
                        help="batch: worker processes (default: the number of cores)")
    parser.add_argument("--cluster", default=None, metavar="ADDRESS",
                        help="batch: run one task per file on the Dask cluster whose scheduler "
                             "is at ADDRESS (e.g. tcp://host:8786) instead of --jobs")
    parser.add_argument("--format", choices=("obj", "glb", "blend"), default="obj",
                        help="batch: format of the files written into the output folder")
    args = parser.parse_args(argv)
    if len(args.paths) < 2:
        raise UsageError("expected INPUT... OUTPUT (at least two paths)")
    patterns, args.output = args.paths[:-1], Path(args.paths[-1])
    args.parser = parser
    args.batch = (len(patterns) > 1 or Path(patterns[0]).is_dir()
                  or (glob.has_magic(patterns[0]) and not Path(patterns[0]).exists()))
    args.inputs = expand_inputs(patterns) if args.batch else [Path(patterns[0])]
    return args


# Options handled by the batch driver itself, not handed to each file's worker.
_DRIVER_ONLY = {"paths", "help", "report", "jobs", "cluster", "format", "png"}


def worker_argv(parser_args, parser):
    """The command-line options of ``parser_args`` that differ from their defaults, as flags
    for a worker process (every option the parser knows, so new options pass through)."""
    out = []
    for action in parser._actions:
        dest = action.dest
        if dest in _DRIVER_ONLY or not action.option_strings:
            continue
        value = getattr(parser_args, dest)
        if value == action.default:
            continue
        flag = action.option_strings[-1]
        if action.nargs == 0:
            out.append(flag)
        else:
            out += [flag, str(value)]
    return out


def expand_inputs(patterns):
    """Files named by ``patterns``: files, folders (their supported files) and glob patterns.
    Raises UsageError naming a pattern that matches nothing usable."""
    files = []
    for pattern in patterns:
        path = Path(pattern)
        if path.is_dir():
            found = sorted(p for p in path.iterdir()
                           if p.is_file() and p.suffix.lower() in INPUT_SUFFIXES)
            if not found:
                raise UsageError(f"input folder {path} holds no {', '.join(INPUT_SUFFIXES)} file")
            files += found
        elif path.exists():
            files.append(path)
        elif glob.has_magic(pattern):
            found = sorted(Path(p) for p in glob.glob(pattern, recursive=True)
                           if Path(p).is_file() and Path(p).suffix.lower() in INPUT_SUFFIXES)
            if not found:
                raise UsageError(f"input pattern {pattern} matches no "
                                 f"{', '.join(INPUT_SUFFIXES)} file")
            files += found
        else:
            raise UsageError(f"input {pattern} does not exist")
    unique = list(dict.fromkeys(p.resolve() for p in files))
    stems = {}
    for p in unique:
        if p.stem in stems:
            raise UsageError(f"inputs {stems[p.stem]} and {p} would both be written as "
                             f"{p.stem}.*: rename one")
        stems[p.stem] = p
    return unique


def _check_writable_file(path: Path, what: str):
    """Raise UsageError unless ``path`` can be created (its folder exists or can be made)."""
    if path.is_dir():
        raise UsageError(f"{what} {path} is a folder")
    folder = path.resolve().parent
    ancestor = folder
    while not ancestor.exists():
        ancestor = ancestor.parent
    if not ancestor.is_dir():
        raise UsageError(f"{what} {path}: {ancestor} is not a folder")
    if not os.access(ancestor, os.W_OK | os.X_OK):
        raise UsageError(f"{what} {path}: folder {ancestor} is not writable")
    if path.exists() and not os.access(path, os.W_OK):
        raise UsageError(f"{what} {path} is not writable")


def _check_range(flag: str, value, prop, method=None) -> None:
    """Raise UsageError when ``value`` is outside the bpy property's min/max or items."""
    keywords = getattr(prop, "keywords", {})
    items = keywords.get("items")
    if items and value not in [i[0] for i in items]:
        of = f" is not an option of {method}" if method else ""
        raise UsageError(f"{flag} {value!r}{of} (expected one of "
                         f"{', '.join(i[0] for i in items)})")
    low, high = keywords.get("min"), keywords.get("max")
    if getattr(prop, "function", None) is bpy.props.IntProperty:  # stored in 32 bits
        low = -2**31 if low is None else low
        high = 2**31 - 1 if high is None else high
    if low is not None and value < low or high is not None and value > high:
        bounds = (f"from {low} to {high}" if low is not None and high is not None
                  else f"at least {low}" if low is not None else f"at most {high}")
        raise UsageError(f"{flag} {value}: out of range (must be {bounds})")


def check_args(args, methods, core_methods):
    """Check every argument before anything is read or written; returns
    ``(method property values, pack property values)``. Raises UsageError naming the argument.
    """
    for path in args.inputs:
        if not path.exists():
            raise UsageError(f"input {path} does not exist")
        if not path.is_file():
            raise UsageError(f"input {path} is not a file")
        if path.suffix.lower() not in INPUT_SUFFIXES:
            raise UsageError(f"input {path}: unsupported format {path.suffix or '(none)'} "
                             f"(use {', '.join(INPUT_SUFFIXES)})")
    if args.batch:
        if args.output.exists() and not args.output.is_dir():
            raise UsageError(f"output folder {args.output} is a file")
        _check_writable_file(args.output / "probe", "output folder")
        if args.png is not None:
            raise UsageError("--png names one image: in a batch, each layout is written beside "
                             "its output")
        if args.jobs is not None and args.jobs < 1:
            raise UsageError(f"--jobs {args.jobs}: must be at least 1")
        if args.cluster is not None:
            if args.jobs is not None:
                raise UsageError("--jobs and --cluster exclude each other (a cluster runs as "
                                 "many files at once as its workers have threads)")
            try:
                cluster.check_address(args.cluster)
            except cluster.ClusterError as ex:
                raise UsageError(str(ex)) from None
    else:
        if args.cluster is not None:
            raise UsageError("--cluster runs a batch (several inputs, a folder or a glob "
                             "pattern, then an output folder)")
        if args.output.suffix.lower() not in OUTPUT_SUFFIXES:
            raise UsageError(f"output {args.output}: unsupported format "
                             f"{args.output.suffix or '(none)'} (use {', '.join(OUTPUT_SUFFIXES)})")
        _check_writable_file(args.output, "output")
        png = args.png or args.output.with_name(args.output.stem + "_uv.png")
        if png.suffix.lower() != ".png":
            raise UsageError(f"--png {png}: must end in .png")
        _check_writable_file(png, "--png")
    if args.report is not None:
        if args.report.suffix.lower() != ".json":
            raise UsageError(f"--report {args.report}: must end in .json")
        _check_writable_file(args.report, "--report")
    if not 1 <= args.size <= MAX_LAYOUT_SIZE:
        raise UsageError(f"--size {args.size}: out of range (must be from 1 to {MAX_LAYOUT_SIZE})")
    if args.uv_name is not None and not 1 <= len(args.uv_name.encode()) <= 63:
        raise UsageError(f"--uv-name {args.uv_name!r}: must be 1 to 63 bytes long")

    known = [m.id for m in methods.METHODS if m.id in core_methods]
    if args.method not in known:
        raise UsageError(f"--method {args.method!r}: unknown; available: {', '.join(known)}")
    info = methods.METHOD_BY_ID[args.method]
    # command-line options onto the operator properties of the chosen method, matched by the
    # keyword each property hands to uvflat.unwrap (tolerances are given as powers of ten)
    given = {"boundary": ("--boundary", args.boundary), "solver": ("--solver", args.solver),
             "max_iterations": ("--max-iterations", args.max_iterations),
             "tolerance": ("--tolerance-exponent", args.tolerance_exponent)}
    method_props = {}
    for keyword, (flag, value) in given.items():
        if value is None:
            continue
        keys = [k for k in info.options if methods.OPTIONS[k].keyword == keyword]
        if not keys:
            raise UsageError(f"{flag} is not an option of {args.method}")
        _check_range(flag, value, methods.OPTIONS[keys[0]].make_property(), args.method)
        method_props[keys[0]] = value

    if args.no_pack and args.pack not in (None, "off"):
        raise UsageError(f"--no-pack contradicts --pack {args.pack}")
    mode = "off" if args.no_pack else (args.pack or "around")
    pack_props = {"pack": mode.upper(), "margin": args.margin,
                  "margin_method": args.margin_method.upper(),
                  "shape_method": args.shape_method.upper(), "rotate": not args.no_rotate,
                  "correct_aspect": not args.no_correct_aspect}
    defaults = methods.common_properties()
    if args.texel_density is not None:
        if not (math.isfinite(args.texel_density) and args.texel_density > 0):
            raise UsageError(f"--texel-density {args.texel_density}: must be a positive number "
                             "of pixels per metre")
        _check_range("--texel-density", args.texel_density, defaults["texel_density"])
        pack_props.update(density_mode="FIXED", texel_density=args.texel_density)
    if args.texture_size is not None:
        _check_range("--texture-size", args.texture_size, defaults["texture_size"])
        pack_props["texture_size"] = args.texture_size
    if not math.isfinite(args.margin):
        raise UsageError(f"--margin {args.margin}: must be a finite number")
    _check_range("--margin", args.margin, defaults["margin"])
    specs = auto_seam_specs()
    auto = {name: getattr(args, name) for name in specs if name not in _AUTO_SEAM_FLAGS_BY_HAND}
    for name, value in auto.items():
        if specs[name]["type"] in ("int", "float"):
            _check_declared(auto_seam_flag(name), value, specs[name])
    if args.sharp_angle is not None and not (math.isfinite(args.sharp_angle)
                                             and 0.0 < args.sharp_angle < 180.0):
        raise UsageError(f"--sharp-angle {args.sharp_angle}: must be between 0 and 180 degrees")
    if args.seams_only:
        if not args.auto_seams:
            raise UsageError("--seams-only plans automatic seams: it contradicts --no-auto-seams")
        if not args.mark_seams:
            raise UsageError("--seams-only marks seams: it contradicts --no-mark-seams")
        target = args.format if args.batch else args.output.suffix.lower().lstrip(".")
        if target != "blend":
            raise UsageError(f"--seams-only writes seams, which only a .blend keeps (output "
                             f"format {target or '(none)'}): write a .blend")
    if args.avoid_group and not args.auto_seams:
        raise UsageError(f"--avoid-group {args.avoid_group!r} steers automatic seams: it "
                         "contradicts --no-auto-seams")
    # automatic seams travel with the packing properties to the operator
    pack_props.update(auto, mark_seams=args.mark_seams, avoid_group=args.avoid_group,
                      prefer_sharp=args.sharp_angle is not None, seams_only=args.seams_only)
    if args.sharp_angle is not None:
        pack_props["sharp_angle"] = math.radians(args.sharp_angle)
    return method_props, pack_props


def export(objects, path: Path):
    suffix = path.suffix.lower()
    path.parent.mkdir(parents=True, exist_ok=True)
    for o in bpy.context.view_layer.objects:
        o.select_set(o in objects)
    bpy.context.view_layer.objects.active = objects[0]
    if suffix == ".obj":
        bpy.ops.wm.obj_export(filepath=str(path), export_selected_objects=True, export_uv=True,
                              export_materials=False)
    elif suffix == ".glb":
        import addon_utils

        addon_utils.enable("io_scene_gltf2", default_set=False)
        bpy.ops.export_scene.gltf(filepath=str(path), export_format="GLB", use_selection=True)
    elif suffix == ".blend":
        bpy.ops.wm.save_as_mainfile(filepath=str(path.resolve()), copy=True)
    else:  # checked by check_args before anything was read
        raise RuntimeError(f"unsupported output format {suffix}")


class ProgressBar:
    """Charts solved so far, as a tqdm bar when tqdm is installed, else a plain text bar."""

    def __init__(self, label):
        self.label = label
        self._bar = None
        self._last = -1
        try:
            import tqdm
        except ImportError:
            self._tqdm = None
        else:
            self._tqdm = tqdm.tqdm

    def __call__(self, objects_done, objects_total, charts_done, charts_total):
        if not charts_total:
            return
        if self._tqdm is not None:
            if self._bar is None:
                self._bar = self._tqdm(total=charts_total, desc=self.label, unit="chart",
                                       leave=False, file=sys.stdout)
            self._bar.update(charts_done - self._bar.n)
            return
        percent = 100 * charts_done // charts_total
        if percent != self._last:
            self._last = percent
            filled = percent // 5
            print(f"\r{self.label} [{'#' * filled}{'.' * (20 - filled)}] {charts_done}/"
                  f"{charts_total} charts", end="", flush=True)

    def close(self):
        if self._bar is not None:
            self._bar.close()
        elif self._last >= 0:
            print(flush=True)


def fail(message) -> int:
    print(f"unwrap.py: error: {message}", file=sys.stderr, flush=True)
    return 1


def _json_number(value):
    """A float as a JSON value (NaN and infinity as strings)."""
    value = float(value)
    if value != value:
        return "nan"
    if value in (float("inf"), float("-inf")):
        return "inf" if value > 0 else "-inf"
    return value


def chart_report(chart):
    """A chart report as plain JSON values (NaN and infinity as strings)."""
    out = {}
    for key, value in chart.as_dict().items():
        if isinstance(value, float) and value != value:
            value = "nan"
        elif isinstance(value, float) and value in (float("inf"), float("-inf")):
            value = "inf" if value > 0 else "-inf"
        out[key] = value
    return out


def file_repairs(source, repairs):
    """``common.repair_repeated_corners``'s repairs as JSON values: the face (counted from 0)
    and its vertices as the file numbers them (from 1 in .obj, from 0 in .off and .ply)."""
    base = 1 if source.suffix.lower() == ".obj" else 0
    return [{"face": f, "corners": [v + base for v in written],
             "kept": None if kept is None else [v + base for v in kept]}
            for f, written, kept in repairs]


def repairs_line(source, repairs, shown=5):
    """One line telling which faces naming a vertex twice were merged or removed."""
    merged = sum(r["kept"] is not None for r in repairs)
    parts = [f"face {r['face']} ({' '.join(map(str, r['corners']))} -> "
             + (" ".join(map(str, r["kept"])) if r["kept"] is not None else "removed") + ")"
             for r in repairs[:shown]]
    more = f", and {len(repairs) - shown} more" if len(repairs) > shown else ""
    return (f"repaired {source}: {len(repairs)} face{'s' * (len(repairs) != 1)} naming a vertex "
            f"more than once ({merged} merged, {len(repairs) - merged} removed): "
            f"{', '.join(parts)}{more}")


def run_single(args, addon, method_props, pack_props) -> int:
    """Unwrap every mesh object of ``args.inputs[0]`` into ``args.output``."""
    mesh_io = addon.mesh_io
    source = args.inputs[0]
    started = time.perf_counter()
    log(f"loading {source}")
    try:
        # the file as written: a non-finite vertex, a face naming a missing vertex, an empty
        # or truncated file is an error naming the element (importers would repair or fail)
        soup = common.check_mesh_file(source)
        common.load_mesh_object(source)
        objects = [o for o in bpy.context.scene.objects if o.type == "MESH"]
        for obj in objects:
            common.check_mesh_object(source, obj)
    except common.MeshFileError as ex:
        return fail(str(ex))
    except (ValueError, RuntimeError, OSError) as ex:
        return fail(f"input {source}: {ex}")
    for obj in objects:
        log(f"loaded '{obj.name}': {len(obj.data.vertices)} vertices, "
            f"{len(obj.data.polygons)} faces")
    n_faces = sum(len(o.data.polygons) for o in objects)
    if not n_faces:
        return fail(f"input {source}: no faces "
                    f"({sum(len(o.data.vertices) for o in objects)} vertices): nothing to unwrap")
    repairs = []
    if soup is not None:
        # a face naming a vertex twice is repaired the same way for every format (the
        # importers would drop some silently), and said so
        _, sizes, repairs = common.repair_repeated_corners(soup[1], soup[2])
        repairs = file_repairs(source, repairs)
        if repairs:
            log(repairs_line(source, repairs))
        if n_faces != len(sizes):
            log(f"note: {source} holds {len(sizes)} faces"
                f"{' after repairs' if repairs else ''}, {n_faces} were read")
    if args.avoid_group and not any(o.vertex_groups.get(args.avoid_group) for o in objects):
        groups = sorted({g.name for o in objects for g in o.vertex_groups})
        have = (f"its vertex groups are {', '.join(map(repr, groups))}" if groups
                else "it has no vertex groups")
        return fail(f"--avoid-group {args.avoid_group!r}: no vertex group of that name in "
                    f"input {source} ({have})")

    if args.seams_from_islands:
        for obj in objects:
            if mesh_io.active_uv_name(obj.data) is None:
                return fail(f"input {source}: --seams-from-islands needs a UV map, "
                            f"'{obj.name}' has none")
        for obj in objects:
            common.seams_from_islands(obj)
            log(f"'{obj.name}': seams from UV islands: {mesh_io.read_seams(obj.data).shape[0]} "
                "seam edges")
    if args.uv_name:
        for obj in objects:
            mesh = obj.data
            layer = mesh.uv_layers.get(args.uv_name) or mesh.uv_layers.new(name=args.uv_name)
            mesh.uv_layers.active = layer

    common.edit_mode(objects)
    log(f"unwrapping {len(objects)} object{'s' * (len(objects) != 1)} with {args.method}")
    bar = ProgressBar(f"{source.name} {args.method}")
    addon.engine.PROGRESS_HOOK = bar
    try:
        result = bpy.ops.uv.uvflat_unwrap(method=args.method, **pack_props, **method_props)
    except RuntimeError as ex:
        text = str(ex).strip()
        if "Traceback" in text:  # a fault of the add-on, not of the input: shown in full
            raise
        # what the operator reports about the input, as one line
        return fail(f"input {source}: {text.removeprefix('Error: ').splitlines()[0]}")
    finally:
        addon.engine.PROGRESS_HOOK = None
        bar.close()
    common.object_mode()
    summary = addon.engine.LAST_SUMMARY
    if "FINISHED" not in result or summary is None:
        log(f"unwrap failed ({result}); nothing written")
        return 1
    log(summary.line())
    # the map just written is the one exporters and renderers must use: active, render map,
    # and first (glTF writes the maps in order, the first is TEXCOORD_0)
    for obj in objects:
        written = mesh_io.active_uv_name(obj.data)
        if written is not None:
            mesh_io.make_first_uv_map(obj.data, written)

    try:
        export(objects, args.output)
    except (RuntimeError, OSError) as ex:
        return fail(f"output {args.output}: {ex}")
    log(f"wrote {args.output}")
    if not args.seams_only:  # Mark Seams Only writes no UVs: no layout image
        png = args.png or args.output.with_name(args.output.stem + "_uv.png")
        uvs, sizes = [], []
        for obj in objects:
            _, _, face_sizes = mesh_io.read_topology(obj.data)
            if mesh_io.active_uv_name(obj.data) is not None:
                uvs.append(mesh_io.read_uv(obj.data))
                sizes.append(face_sizes)
        try:
            common.save_layout(png, np.concatenate(uvs) if uvs else np.zeros((0, 2)),
                               np.concatenate(sizes) if sizes else np.zeros(0, dtype=np.int64),
                               size=args.size, title=f"{source.name} - {args.method}")
        except OSError as ex:
            return fail(f"--png {png}: {ex}")
        log(f"wrote {png}")
    status = 2 if summary.failed else 0
    if args.report is not None:
        report = {
            "file": str(source), "output": str(args.output), "method": args.method,
            "status": "charts failed" if status else "ok", "seconds": time.perf_counter() - started,
            "summary": summary.line(), "non_manifold_edges": summary.non_manifold_edges,
            "inconsistent_edges": summary.inconsistent_edges,
            "repairs": repairs,
            "texture_size": summary.texture_size,
            "objects": {name: [dict(chart_report(c), texel_density=_json_number(
                               summary.px_per_metre(name)[c.id])
                               if name in summary.chart_density else "nan")
                               for c in r.charts]
                        for name, r in summary.results.items()},
        }
        try:
            args.report.parent.mkdir(parents=True, exist_ok=True)
            args.report.write_text(json.dumps(report, indent=1))
        except OSError as ex:
            return fail(f"--report {args.report}: {ex}")
        log(f"wrote {args.report}")
    return status


def _file_line(source, rc, report, stderr, out):
    if report is None:
        last = [line for line in stderr.strip().splitlines() if line.strip()]
        return {"file": source.name, "status": "error", "objects": 0, "charts": 0, "failed": 0,
                "flips": 0, "seconds": 0.0, "output": "-",
                "detail": last[-1] if last else f"exit status {rc}"}
    charts = [c for cs in report["objects"].values() for c in cs]
    repaired = len(report.get("repairs", ()))
    detail = report["summary"] + (f"; {repaired} face{'s' * (repaired != 1)} naming a vertex "
                                  "twice repaired" if repaired else "")
    return {"file": source.name, "status": report["status"], "objects": len(report["objects"]),
            "charts": len(charts), "failed": sum(c["status"] == "failed" for c in charts),
            "flips": sum(int(c["flips"]) for c in charts), "seconds": report["seconds"],
            "output": str(out), "detail": detail}


def _on_threads(jobs, call, items):
    """``call(*item)`` for every item, ``jobs`` at a time; yields ``(item, result)``."""
    log(f"{len(items)} files, {jobs} worker process{'es' * (jobs != 1)}")
    with ThreadPoolExecutor(max_workers=jobs) as pool:
        futures = {pool.submit(call, *item): item for item in items}
        for future in as_completed(futures):
            try:
                result = future.result()
            except OSError as ex:  # e.g. the output folder went away: that file's error
                result = (1, None, f"{type(ex).__name__}: {ex}")
            yield futures[future], result


def run_batch(args) -> int:
    """One worker process per file (``--jobs`` at a time on this machine, or one task each
    on the workers of ``--cluster``); a line per file, a final table."""
    client, unwrap_file = None, cluster.unwrap_file
    if args.cluster is not None:
        try:  # reached before anything is written
            client, unwrap_file = cluster.connect(args.cluster, log=log)
        except cluster.ClusterError as ex:
            return fail(ex)
    args.output.mkdir(parents=True, exist_ok=True)
    forwarded = worker_argv(args, args.parser)
    run_id = f"uvflat-{uuid.uuid4().hex[:8]}"
    # the same per-file function for --jobs and --cluster (there, as the cluster imports
    # cluster.py): the same files either way
    call = functools.partial(unwrap_file, script=Path(__file__).resolve(),
                             options=forwarded, cwd=os.getcwd(), run_id=run_id)
    items = [(source, args.output / f"{source.stem}.{args.format}") for source in args.inputs]
    if client is not None:
        log(f"{len(items)} files, one task each on the cluster")
        results = cluster.map_on_cluster(client, call, items)
    else:
        results = _on_threads(args.jobs or os.cpu_count() or 1, call, items)
    rows, reports, worst = [], [], 0
    try:
        for (source, out), (rc, data, stderr) in results:
            row = _file_line(source, rc, data, stderr, out)
            rows.append(row)
            if data is not None:
                reports.append(data)
            worst = max(worst, 1 if rc not in (0, 2) else rc)
            log(f"{row['file']}: {row['status']}: {row['detail']}")
    finally:
        if client is not None:
            client.close()
        cluster.remove_leftovers(args.output, run_id)
    rows.sort(key=lambda r: r["file"])
    width = max(len(r["file"]) for r in rows)
    print(f"{'file':<{width}}  {'status':<13} {'objects':>7} {'charts':>7} {'failed':>6} "
          f"{'flips':>6} {'seconds':>8}  output")
    for r in rows:
        print(f"{r['file']:<{width}}  {r['status']:<13} {r['objects']:>7} {r['charts']:>7} "
              f"{r['failed']:>6} {r['flips']:>6} {r['seconds']:>8.2f}  {r['output']}")
    n_bad = sum(r["status"] != "ok" for r in rows)
    print(f"{len(rows)} files, {len(rows) - n_bad} ok, {n_bad} not", flush=True)
    if args.report is not None:
        args.report.parent.mkdir(parents=True, exist_ok=True)
        args.report.write_text(json.dumps({"files": sorted(reports, key=lambda d: d["file"]),
                                           "table": rows}, indent=1))
        log(f"wrote {args.report}")
    return worst


def main(argv=None):
    try:
        args = parse_args(sys.argv[1:] if argv is None else argv)
    except UsageError as ex:
        return fail(ex)
    common.reset_scene()
    addon = common.load_addon()
    import uvflat

    try:
        method_props, pack_props = check_args(args, addon.methods, uvflat.METHODS)
    except UsageError as ex:
        return fail(ex)
    if args.batch:
        return run_batch(args)
    return run_single(args, addon, method_props, pack_props)


if __name__ == "__main__":
    sys.exit(main())
