# SPDX-License-Identifier: GPL-3.0-or-later
"""Correct aspect: make UV islands undistorted in the pixels of a non-square texture.

As ``uv.unwrap``'s *Correct Aspect*: with an image ``aspect = width / height`` other than 1,
each new island is scaled along U by ``1 / aspect`` about its own centre, so that a square
on the surface covers a square of pixels. The image is the UV editor's one when the operator
runs there, else the image of the object's active material (its active image texture node,
or its first image texture node with an image).
"""

from __future__ import annotations

import numpy as np


def _image_size(image):
    size = tuple(getattr(image, "size", (0, 0)) or (0, 0))
    return size if len(size) == 2 and size[0] > 0 and size[1] > 0 else None


def material_image(obj):
    """The image of ``obj``'s active material: its active image texture node, else the first
    image texture node holding an image; ``None`` when there is none."""
    material = getattr(obj, "active_material", None)
    tree = getattr(material, "node_tree", None) if material is not None else None
    if tree is None:
        return None
    active = tree.nodes.active
    if active is not None and active.type == "TEX_IMAGE" and active.image is not None:
        return active.image
    for node in tree.nodes:
        if node.type == "TEX_IMAGE" and node.image is not None:
            return node.image
    return None


def material_aspect(obj) -> float:
    """``width / height`` of the image of ``obj``'s active material (1.0 when there is none):
    the aspect Blender's packer works in (it rotates islands in that image's pixels)."""
    image = material_image(obj)
    size = _image_size(image) if image is not None else None
    return size[0] / size[1] if size is not None else 1.0


def image_aspect(context, obj) -> float:
    """``width / height`` of the texture ``obj``'s UVs are for (1.0 when unknown)."""
    space = getattr(context, "space_data", None)
    if space is not None and getattr(space, "type", "") == "IMAGE_EDITOR":
        size = _image_size(getattr(space, "image", None))
        if size is not None:
            return size[0] / size[1]
    image = material_image(obj)
    size = _image_size(image) if image is not None else None
    return size[0] / size[1] if size is not None else 1.0


def correct(uv, corners, chart_of_corner, aspect):
    """Scale U of the ``corners`` of every chart by ``1 / aspect`` about the chart's centre
    (the middle of its corners' U range), in place. ``chart_of_corner``: chart of every corner."""
    if aspect == 1.0 or not corners.any():
        return uv
    charts = chart_of_corner[corners]
    u = uv[corners, 0].astype(np.float64)
    size = charts.max() + 1
    low = np.full(size, np.inf)
    high = np.full(size, -np.inf)
    np.minimum.at(low, charts, u)
    np.maximum.at(high, charts, u)
    centre = 0.5 * (low + high)
    uv[corners, 0] = centre[charts] + (u - centre[charts]) / aspect
    return uv
