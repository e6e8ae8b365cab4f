"""Weber-Penn tree model speaking Blender Sapling's parameter dictionary (TreeSketchNet keys)."""

from . import species
from .grow import Skeleton, grow
from .mesh import TreeMesh, build_mesh
from .params import (
    HEADS,
    PARAMS,
    ParamError,
    ParamSpec,
    TreeParams,
    default_params,
    load_params,
    save_params,
    validate,
)

__all__ = [
    "HEADS",
    "PARAMS",
    "ParamError",
    "ParamSpec",
    "Skeleton",
    "TreeMesh",
    "TreeParams",
    "build_mesh",
    "default_params",
    "grow",
    "load_params",
    "save_params",
    "species",
    "validate",
]
