"""What the scripts run inside Blender share (``blender_species.py``,
``blender_time_sapling.py``): they find it beside them."""

import addon_utils  # type: ignore[import-not-found]
import bpy  # type: ignore[import-not-found]


def enable_sapling() -> None:
    addon_utils.enable("add_curve_sapling", default_set=True)


def clear() -> None:
    """An empty scene: no objects, and no curve or mesh data left of removed ones."""
    for o in list(bpy.data.objects):
        bpy.data.objects.remove(o)
    for c in list(bpy.data.curves):
        bpy.data.curves.remove(c)
    for m in list(bpy.data.meshes):
        bpy.data.meshes.remove(m)
