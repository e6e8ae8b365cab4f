"""Weber-Penn tree model speaking Blender Sapling's parameter dictionary (TreeSketchNet keys)."""

from . import species
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
    "TreeParams",
    "default_params",
    "load_params",
    "save_params",
    "species",
    "validate",
]

try:  # the generator and mesher arrive in their own modules
    from .grow import Skeleton, grow  # noqa: F401
    from .mesh import TreeMesh, build_mesh  # noqa: F401

    __all__ += ["Skeleton", "TreeMesh", "build_mesh", "grow"]
except ImportError:  # pragma: no cover - during bootstrap only
    pass
