# SPDX-License-Identifier: GPL-3.0-or-later
"""The table of unwrap methods and their options: the single place to add a method.

To add a method (``abf``, ``arap``, ``slim``, ``mips``, ``scaffold`` …): append one
:class:`MethodInfo` to :data:`METHODS`; if it takes options the table does not know yet, add
them to :data:`OPTIONS`.  The operator, the sidebar defaults, the redo panel and the batch
scripts all read these two tables.

The automatic-seams properties are built from the core's declared options
(``uvflat.AUTO_SEAM_OPTIONS``, :data:`AUTO_SEAM_SPECS`): their defaults, bounds and choices are
the core's, only labels, descriptions and display settings are written here.
"""

from __future__ import annotations

import math

import bpy
from dataclasses import dataclass
from typing import Any, Callable

from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, StringProperty

from . import engine


@dataclass(frozen=True)
class MethodInfo:
    id: str            # name understood by uvflat.unwrap(method=...)
    label: str
    description: str
    options: tuple[str, ...]  # keys of OPTIONS shown and passed for this method


METHODS: tuple[MethodInfo, ...] = (
    MethodInfo("tutte", "Tutte", "Uniform barycentric map, boundary fixed to a convex shape; "
               "never flips (Tutte 1963)", ("boundary",)),
    MethodInfo("harmonic", "Harmonic", "Cotangent-weight barycentric map, boundary fixed "
               "(Eck et al. 1995)", ("boundary",)),
    MethodInfo("mean_value", "Mean Value", "Mean-value-weight barycentric map, boundary fixed; "
               "never flips (Floater 2003)", ("boundary",)),
    MethodInfo("lscm", "LSCM", "Least squares conformal map, free boundary (Lévy et al. 2002); "
               "without pins, fixed on the whole outline as Spectral Conformal", ()),
    MethodInfo("spectral", "Spectral Conformal", "Conformal map from a generalized eigenproblem, "
               "free boundary (Mullen et al. 2008)", ("max_iterations", "tolerance_exponent")),
    MethodInfo("bff", "BFF", "Boundary first flattening: the conformal map of least area "
               "distortion, the outline's lengths kept; the map automatic seams plan their "
               "cuts on (Sawhney & Crane 2017)", ()),
    MethodInfo("abf", "ABF++", "Angle based flattening: solves for the triangle angles under the "
               "planarity constraints, then lays the chart out; free or convex boundary "
               "(Sheffer & de Sturler 2001; Sheffer et al. 2005)",
               ("abf_solver", "abf_boundary", "abf_max_iterations", "abf_tolerance_exponent")),
    MethodInfo("arap", "ARAP", "As-rigid-as-possible: local/global iterations from LSCM towards "
               "the closest isometry, free boundary; may fold triangles (Liu et al. 2008)",
               ("arap_iterations", "arap_tolerance_exponent")),
    MethodInfo("slim", "SLIM", "Symmetric Dirichlet energy (minimum stretch) from a flip-free "
               "start with a flip-free line search; never flips a triangle "
               "(Rabinovich et al. 2017)", ("slim_iterations", "slim_tolerance_exponent")),
    MethodInfo("mips", "MIPS", "Most isometric parameterization energy (conformal), Newton "
               "from a flip-free start with a flip-free line search, free boundary; never "
               "flips a triangle (Hormann & Greiner 2000)",
               ("mips_iterations", "mips_tolerance_exponent")),
    MethodInfo("scaffold", "Scaffold (Bijective)", "Symmetric Dirichlet energy on the chart "
               "plus a re-triangulated scaffold of the free space around it: no flipped "
               "triangles and no self-overlapping island (Jiang et al. 2017)",
               ("scaffold_iterations", "scaffold_tolerance_exponent")),
)

METHOD_BY_ID = {m.id: m for m in METHODS}


@dataclass(frozen=True)
class OptionInfo:
    keyword: str                              # keyword argument of uvflat.unwrap
    make_property: Callable[[], Any]          # a fresh bpy property (one per class using it)
    to_core: Callable[[Any], Any] = lambda value: value


def _iterations(description: str, default: int, soft_max: int) -> OptionInfo:
    """An iteration limit (keyword ``max_iterations``)."""
    return OptionInfo(
        "max_iterations",
        lambda: IntProperty(name="Iterations", description=description, default=default,
                            min=1, soft_max=soft_max),
    )


def _tolerance(description: str, default: int, lowest: int = -15, highest: int = -1) -> OptionInfo:
    """A tolerance given as a power of ten (keyword ``tolerance``)."""
    return OptionInfo(
        "tolerance",
        lambda: IntProperty(name="Tolerance (10^x)",
                            description=f"{description}, as a power of ten",
                            default=default, min=lowest, max=highest),
        lambda exponent: 10.0 ** int(exponent),
    )


_ENERGY_CHANGE = "Stop when the energy decreases by less than this (relative)"
_ENERGY_CHANGE_PREDICTED = _ENERGY_CHANGE + ", or is predicted to at the next iteration"

OPTIONS: dict[str, OptionInfo] = {
    "boundary": OptionInfo(
        "boundary",
        lambda: EnumProperty(
            name="Boundary",
            description="Shape the chart boundary is fixed to (by arc length)",
            items=(("circle", "Circle", "Boundary on the unit circle"),
                   ("square", "Square", "Boundary on the unit square"),
                   ("virtual", "Virtual", "A band of virtual triangles around the boundary goes "
                                          "on the unit circle; the real boundary settles "
                                          "freely inside it: less distortion (Lee et al. 2002)")),
            default="circle",
        ),
    ),
    "max_iterations": _iterations("Maximum iterations of the eigen solver", 200, 5000),
    "tolerance_exponent": _tolerance(
        "Convergence tolerance of the eigen solver (change of the normalised iterate)", -10, -16),
    "abf_solver": OptionInfo(
        "solver",
        lambda: EnumProperty(
            name="Solver",
            description="Linear algebra of each Newton step",
            items=(("abf++", "ABF++", "Block elimination onto the vertex constraints (fast)"),
                   ("abf", "ABF", "The full constrained system by sparse LU (slow reference)")),
            default="abf++",
        ),
    ),
    "abf_boundary": OptionInfo(
        "boundary",
        lambda: EnumProperty(
            name="Boundary",
            description="Constraint on the angles of the chart's outer boundary",
            items=(("free", "Free", "No constraint: the least angle distortion"),
                   ("convex", "Convex", "Every outer boundary angle at most 180 degrees: a convex "
                                        "outline")),
            default="free",
        ),
    ),
    "abf_max_iterations": _iterations(
        "Maximum Newton iterations of the angle solve (a chart that does not converge falls "
        "back to LSCM)", 30, 200),
    "abf_tolerance_exponent": _tolerance(
        "Largest violation of the angle constraints accepted", -5, -14, -3),
    "arap_iterations": _iterations("Maximum local/global iterations", 100, 1000),
    "arap_tolerance_exponent": _tolerance(
        "Stop when the energy changes by less than this (relative)", -6),
    "slim_iterations": _iterations(
        "Maximum SLIM iterations (each one a reweighted solve and a flip-free line search)",
        15, 500),
    "slim_tolerance_exponent": _tolerance(_ENERGY_CHANGE_PREDICTED, -4),
    "mips_iterations": _iterations(
        "Maximum Newton iterations (each one a projected-Hessian solve and a flip-free line "
        "search)", 50, 500),
    "mips_tolerance_exponent": _tolerance(_ENERGY_CHANGE, -6),
    "scaffold_iterations": _iterations(
        "Maximum iterations (each one a scaffold rebuild, a reweighted solve and a flip-free "
        "line search)", 100, 1000),
    "scaffold_tolerance_exponent": _tolerance(_ENERGY_CHANGE, -4),
}


@dataclass(frozen=True)
class PresetInfo:
    id: str
    label: str
    method: str | None   # None: the method chosen under Advanced
    description: str


# The choices most artists need, each naming its trade-off; every method stays under Advanced.
PRESETS: tuple[PresetInfo, ...] = (
    PresetInfo("FAST", "Fast", "bff",
               "BFF: one linear solve, the quickest. Keeps angles and the outline's lengths, "
               "and Auto Seams plan their cuts on its map; unlike Balanced it promises no "
               "flips (a fold it leaves is cut away by Auto Seams, or reported)"),
    PresetInfo("BALANCED", "Balanced", "abf",
               "ABF++: solves the angles first, then lays the island out. The best overall "
               "atlas on closed, open and seamed meshes, up to about twice the time of Fast"),
    PresetInfo("LEAST_STRETCH", "Least Stretch", "slim",
               "SLIM: the most even texel density and never a flipped triangle, at the "
               "cost of the longest solve"),
    PresetInfo("ADVANCED", "Advanced", None,
               "Choose any of the eleven methods and its options"),
)
PRESET_BY_ID = {p.id: p for p in PRESETS}
DEFAULT_PRESET = "BALANCED"
DEFAULT_METHOD = PRESET_BY_ID[DEFAULT_PRESET].method


def _preset_changed(self, _context):
    """A preset sets its method (Advanced keeps the method as it is)."""
    method = PRESET_BY_ID[self.preset].method
    if method is not None and self.method != method:
        self.method = method


def _method_changed(self, _context):
    """A method other than the preset's turns the preset to Advanced."""
    method = PRESET_BY_ID[self.preset].method
    if method is not None and self.method != method:
        self.preset = "ADVANCED"


def chosen_method(props) -> str:
    """The method ``props`` (operator or scene defaults) asks for: the preset's, or under
    Advanced the chosen method. A caller that named a method but no preset (a script's
    ``bpy.ops.uv.uvflat_unwrap(method="tutte")``, a keymap item) gets that method."""
    preset = PRESET_BY_ID.get(getattr(props, "preset", "ADVANCED"), PRESET_BY_ID["ADVANCED"])
    if preset.method is None:
        return props.method
    # an operator answers through its properties
    is_set = getattr(getattr(props, "properties", props), "is_property_set", None)
    if is_set is not None and is_set("method") and not is_set("preset"):
        return props.method
    return preset.method


def settle_preset(props) -> None:
    """Make ``props``' preset and method agree with :func:`chosen_method` (what the redo panel
    then shows): a named method without a preset is Advanced; a preset sets its method."""
    method = chosen_method(props)
    if PRESET_BY_ID[props.preset].method not in (None, method):
        props.preset = "ADVANCED"
    if props.method != method:
        props.method = method


def common_properties() -> dict[str, Any]:
    """Fresh bpy properties shared by the operator and the scene defaults."""
    props: dict[str, Any] = {
        "preset": EnumProperty(
            name="Preset",
            description="Speed against quality of the unwrap",
            items=tuple((p.id, p.label, p.description) for p in PRESETS),
            default=DEFAULT_PRESET,
            update=_preset_changed,
        ),
        "method": EnumProperty(
            name="Method",
            description="Parameterization method (Advanced preset)",
            items=tuple((m.id, m.label, m.description) for m in METHODS),
            default=DEFAULT_METHOD,
            update=_method_changed,
        ),
        "pack": EnumProperty(
            name="Pack",
            description="Packing of the new islands with Blender's packer",
            items=(("AROUND", "Around Others", "Pack the new islands into the free space of "
                                               "the UDIM tile their faces were in, at the texel "
                                               "density of the islands already there; every "
                                               "other island stays exactly where it is"),
                   ("ALL", "Whole Tile", "Pack the new islands over the whole UDIM tile their "
                                         "faces were in, scaled to fill it, as Blender's "
                                         "Unwrap does; other islands are not moved but may "
                                         "be overlapped"),
                   ("OFF", "Off", "Fit each new island to where its faces' previous UVs were "
                                  "(islands without previous UVs are packed around the others)")),
            default="AROUND",
        ),
        "correct_aspect": BoolProperty(
            name="Correct Aspect",
            description="Scale the new islands for a non-square texture (the UV editor's "
                        "image, else the active material's image texture), as Blender's "
                        "Unwrap does",
            default=True,
        ),
        "orient": BoolProperty(
            name="Orient",
            description="Turn each new island to its smallest bounding box before packing; "
                        "with Rotate, the packer then turns islands by quarter turns only",
            default=True,
        ),
        # Blender's own defaults of uv.pack_islands for the three below
        "rotate": BoolProperty(
            name="Rotate",
            description="Rotate islands to pack them tighter",
            default=True,
        ),
        "shape_method": EnumProperty(
            name="Shape",
            description="Island shape used by Blender's packer. The exact and convex shapes "
                        "are searched island against island: beyond a few islands the packer "
                        "is given convex hulls, then bounding boxes, so that it stays quick",
            items=(("CONCAVE", "Exact Shape (Concave)", "Tightest, slowest; for a few islands"),
                   ("CONVEX", "Convex Hull", "Tighter than bounding boxes"),
                   ("AABB", "Bounding Box", "Fastest, whatever the number of islands")),
            default="CONCAVE",
        ),
        "margin_method": EnumProperty(
            name="Margin Method",
            description="How the margin is measured",
            items=(("SCALED", "Scaled", "Margin scaled with the islands (as in Blender's Unwrap)"),
                   ("ADD", "Add", "Margin added to the island size"),
                   ("FRACTION", "Fraction", "Margin as a fraction of the UV tile")),
            default="SCALED",
        ),
        "margin": FloatProperty(
            name="Margin",
            description="Space between packed islands",
            default=0.001, min=0.0, max=1.0, precision=3, step=0.1,
        ),
        **density_properties(),
    }
    props.update(auto_seam_properties())
    for key, option in OPTIONS.items():
        props[key] = option.make_property()
    return props


# The core's declared automatic-seams options (uvflat.AUTO_SEAM_OPTIONS) by name: the
# properties below take their defaults, bounds and choices from it.
def _core():
    """The uvflat module; an ImportError (the add-on cannot load) when it is missing."""
    try:
        return engine.import_core()
    except engine.UnwrapError as ex:  # pragma: no cover - depends on the installation
        raise ImportError(f"uvflat: {ex}") from ex


AUTO_SEAM_SPECS: dict[str, dict[str, Any]] = {s["name"]: s for s in _core().AUTO_SEAM_OPTIONS}

# Options set on the Blender side: avoid_vertices comes from the vertex group named by
# avoid_group (engine.py), sharp_angle is on only with prefer_sharp.
BLENDER_SIDE_OPTIONS = ("avoid_vertices",)

# Words for the symmetry choices (the identifiers are the core's names).
SYMMETRY_ITEMS: dict[str, tuple[str, str]] = {
    "none": ("None", "No symmetry: each island is cut on its own"),
    "x": ("X", "Mirror across the plane through the island's centre facing X (left/right "
               "for a character facing -Y)"),
    "y": ("Y", "Mirror across the plane through the island's centre facing Y"),
    "z": ("Z", "Mirror across the plane through the island's centre facing Z"),
    "auto": ("Auto", "The first of the island's principal axes across which it is its own "
                     "mirror image"),
}


def _from_spec(name: str, label: str, description: str, **ui) -> Any:
    """A fresh bpy property for the declared option ``name``: its type, default, bounds and
    choices come from :data:`AUTO_SEAM_SPECS`; ``ui`` adds display settings and may narrow
    the bounds (never widen them: checked here)."""
    spec = AUTO_SEAM_SPECS[name]
    kind = spec["type"]
    # an option that is off by default (sharp_angle) gets the value it starts from when on
    default = ui.pop("default") if spec["default"] is None else spec["default"]
    if kind == "bool":
        return BoolProperty(name=label, description=description, default=default, **ui)
    if kind == "choice":
        return EnumProperty(name=label, description=description, default=default,
                            items=tuple((c, *SYMMETRY_ITEMS[c]) if name == "symmetry" else
                                        (c, c.title(), "") for c in spec["choices"]), **ui)
    low = ui.pop("min", spec["min"])
    high = ui.pop("max", spec["max"])
    if spec["min"] is not None:
        assert low > spec["min"] or (low == spec["min"] and not spec["min_exclusive"]), name
    if spec["max"] is not None:
        assert high < spec["max"] or (high == spec["max"] and not spec["max_exclusive"]), name
    bounds = {k: v for k, v in (("min", low), ("max", high)) if v is not None}
    if kind == "int":
        return IntProperty(name=label, description=description, default=default, **bounds, **ui)
    if kind == "float":
        return FloatProperty(name=label, description=description, default=default, **bounds,
                             **ui)
    raise ValueError(f"{name}: no property for options of type {kind}")


def density_properties() -> dict[str, Any]:
    """Fresh bpy properties of the new islands' texel density. Not remembered from one call
    of the operator to the next (``SKIP_SAVE``): a script or shortcut that names no density
    gets Auto, and invoking it copies the sidebar's."""
    return {
        "density_mode": EnumProperty(
            name="Texel Density",
            description="Texel density of the new islands",
            items=(("AUTO", "Auto", "As the packing does it: around others their density, "
                                    "whole tile scaled to fill it, off where the old UVs were"),
                   ("MATCH", "Match Existing", "The density of the islands left alone, whatever "
                                               "the packing (the packer scales nothing)"),
                   ("FIXED", "Fixed", "Pixels per metre of surface on a texture of Texture "
                                      "Size pixels; packed without scaling, so islands may "
                                      "not fit in the tile")),
            default="AUTO", options={"SKIP_SAVE"},
        ),
        "texel_density": FloatProperty(
            name="Px per Metre",
            description="Texture pixels per metre of surface (world size) with a Fixed texel "
                        "density",
            default=1024.0, min=1e-3, max=1e7, soft_min=1.0, soft_max=8192.0, precision=1,
            options={"SKIP_SAVE"},
        ),
        "texture_size": IntProperty(
            name="Texture Size",
            description="Texture width in pixels (along U) of the Fixed texel density and "
                        "of the densities the chart list shows; with Correct Aspect the height "
                        "follows the image's aspect",
            default=1024, min=1, max=65536, soft_max=16384, options={"SKIP_SAVE"},
        ),
    }


DENSITY_SETTING_NAMES: tuple[str, ...] = ("density_mode", "texel_density", "texture_size")


def auto_seam_properties() -> dict[str, Any]:
    """Fresh bpy properties of automatic seams (closed and higher-genus charts)."""
    return {
        "auto_seams": _from_spec(
            "auto_seams", "Auto Seams",
            "Cut closed charts and charts with handles open through a few cone singularities, "
            "so every selected face unwraps. Your own seams are kept and used first"),
        "max_stretch": _from_spec(
            "max_stretch", "Max Stretch",
            "How much texel density may vary inside one island before another cone or cut is "
            "added", min=1.05, max=100.0, soft_max=8.0, precision=2, step=10),
        "max_cones": _from_spec(
            "max_cones", "Max Cones",
            "Most cone singularities per chart (a closed sphere always gets 2)", soft_max=64),
        "prefer_sharp": BoolProperty(
            name="Prefer Sharp Edges",
            description="Let new seams run along edges sharper than Sharp Angle",
            default=AUTO_SEAM_SPECS["sharp_angle"]["default"] is not None,
        ),
        # the angle Prefer Sharp Edges starts from (the core's default is no preference)
        "sharp_angle": _from_spec(
            "sharp_angle", "Sharp Angle", "Dihedral angle from which an edge counts as sharp",
            min=math.radians(1.0), max=math.radians(179.0), subtype="ANGLE",
            default=math.radians(30.0)),
        "symmetry": _from_spec(
            "symmetry", "Symmetry",
            "Mirror plane the new seams keep: on an island that is its own mirror image the "
            "cuts are mirrored, so both halves unwrap alike"),
        "visibility_weight": _from_spec(
            "visibility_weight", "Seam Visibility",
            "How much dearer a seam is on exposed surface than in hidden places (ambient "
            "occlusion): higher hides seams more, 0 ignores visibility",
            soft_max=4.0, precision=2, step=10),
        "same_seams": _from_spec(
            "same_seams", "Same Seams",
            "Plan the cuts of SLIM, ARAP and Scaffold as for the other methods, so switching "
            "methods keeps the seams. Off: those three, which even out area, start from the "
            "cone points alone and usually get fewer seams and islands"),
        "avoid_group": StringProperty(
            name="Avoid Seams",
            description="Vertex group where new seams must not go (e.g. the face); empty for "
                        "none",
            default="",
        ),
        "mark_seams": BoolProperty(
            name="Mark Seams",
            description="Mark the cuts it made as edge seams, so you can see and edit them "
                        "and unwrap again",
            default=True,
        ),
        "seams_only": BoolProperty(
            name="Mark Seams Only",
            description="Plan the seams automatic seams would cut and mark them, without "
                        "writing any UVs: review and edit them, then unwrap",
            default=False,
        ),
    }


AUTO_SEAM_NAMES: tuple[str, ...] = tuple(auto_seam_properties().keys())


def auto_seam_options(props) -> dict[str, Any]:
    """The automatic-seams keywords of ``uvflat.unwrap`` from the properties in ``props``:
    every declared option but those set on the Blender side (:data:`BLENDER_SIDE_OPTIONS`)."""
    out: dict[str, Any] = {}
    for name, spec in AUTO_SEAM_SPECS.items():
        if name in BLENDER_SIDE_OPTIONS:
            continue
        if name == "sharp_angle":
            out[name] = float(props.sharp_angle) if props.prefer_sharp else None
            continue
        cast = {"bool": bool, "int": int, "float": float, "choice": str}[spec["type"]]
        out[name] = cast(getattr(props, name))
    return out


SETTING_NAMES: tuple[str, ...] = tuple(common_properties().keys())
PACK_SETTING_NAMES: tuple[str, ...] = ("pack", "shape_method", "margin_method", "margin", "rotate",
                                       "orient")


def pack_settings(props) -> dict[str, Any]:
    """Keyword arguments of ``engine.PackSettings`` from ``props`` (operator or defaults)."""
    return {"mode": props.pack, "margin": props.margin, "margin_method": props.margin_method,
            "shape_method": props.shape_method, "rotate": props.rotate,
            "orient": getattr(props, "orient", True),
            "density": getattr(props, "density_mode", "AUTO"),
            "texel_density": float(getattr(props, "texel_density", 1024.0)),
            "texture_size": int(getattr(props, "texture_size", 1024))}


def add_properties(cls):
    """Class decorator: put the shared properties into ``cls.__annotations__``."""
    annotations = dict(getattr(cls, "__annotations__", {}))
    annotations.update(common_properties())
    cls.__annotations__ = annotations
    return cls


def core_options(props, method=None) -> dict[str, Any]:
    """The keyword options of ``uvflat.unwrap`` for ``method`` (default: the one ``props``
    asks for, :func:`chosen_method`), with their values from ``props``."""
    info = METHOD_BY_ID[method or chosen_method(props)]
    return {OPTIONS[key].keyword: OPTIONS[key].to_core(getattr(props, key)) for key in info.options}


def draw_settings(layout, props) -> None:
    """Draw the method and only that method's options (redo panel and sidebar)."""
    layout.use_property_split = True
    layout.use_property_decorate = False
    layout.prop(props, "preset")
    if PRESET_BY_ID[props.preset].method is None:  # Advanced: every method and its options
        layout.prop(props, "method")
        for key in METHOD_BY_ID[props.method].options:
            layout.prop(props, key)
    layout.prop(props, "auto_seams")
    col = layout.column()
    col.active = props.auto_seams
    col.prop(props, "max_stretch")
    col.prop(props, "max_cones")
    col.prop(props, "prefer_sharp")
    sub = col.column()
    sub.active = props.auto_seams and props.prefer_sharp
    sub.prop(props, "sharp_angle")
    col.prop(props, "symmetry")
    col.prop(props, "visibility_weight")
    col.prop(props, "same_seams")
    obj = getattr(bpy.context, "active_object", None)
    if obj is not None and obj.type == "MESH":
        col.prop_search(props, "avoid_group", obj, "vertex_groups")
    else:
        col.prop(props, "avoid_group")
    col.prop(props, "mark_seams")
    col.prop(props, "seams_only")
    layout.prop(props, "correct_aspect")
    layout.prop(props, "pack")
    col = layout.column()
    col.active = props.pack != "OFF"
    for key in PACK_SETTING_NAMES[1:]:
        col.prop(props, key)
    layout.prop(props, "density_mode")
    col = layout.column()
    col.active = props.density_mode == "FIXED"
    col.prop(props, "texel_density")
    col.prop(props, "texture_size")


def apply_defaults(props, defaults) -> list[str]:
    """Copy the scene ``defaults`` into operator ``props`` for every setting the caller did not
    set (``props.is_property_set``): a keymap item, a pie menu or
    ``layout.operator(...).method = "abf"`` keeps what it asked for. Returns the names copied.
    """
    copied = []
    method_set, preset_set = props.is_property_set("method"), props.is_property_set("preset")
    for name in SETTING_NAMES:
        if props.is_property_set(name):
            continue
        if name == "preset" and method_set:  # a named method runs as it is: Advanced
            props.preset = "ADVANCED"
            continue
        if name == "method" and preset_set and PRESET_BY_ID[props.preset].method is not None:
            props.method = PRESET_BY_ID[props.preset].method
            continue
        setattr(props, name, getattr(defaults, name))
        copied.append(name)
    return copied
