"""strata for Python: anisotropic, density-controlled, stratified (blue-noise) sampling
of triangle meshes, with numpy arrays in and out.

    >>> import strata_sampling as ss
    >>> V, F = ss.load_mesh("bunny.obj")
    >>> s = ss.sample(V, F, 10_000, seed=1)
    >>> s.positions.shape, s.face_ids.dtype
    ((10000, 3), dtype('uint32'))

``sample`` preprocesses and samples in one call; ``Sampler`` preprocesses once (the
expensive part) and then draws any count as often as wanted. Fields say where samples
are denser and in which direction they are closer: see ``constant``, ``curvature``,
``designed``, ``isotropic``, ``frames`` and ``tensors``, or pass a scene file's field
description (RON text) directly.

Sample arrays (all C-contiguous and writable, over the buffers the engine wrote, no
copy made on return; a freed result's memory is reused by the sampler's next draw):

================  =======  ========  =================================================
attribute         shape    dtype     meaning
================  =======  ========  =================================================
positions         (n, 3)   float32   world position
normals           (n, 3)   float32   unit surface normal (interpolated vertex normals)
face_ids          (n,)     uint32    face the sample lies on
barycentrics      (n, 3)   float32   weights of the face's corners 0, 1, 2 (sum 1)
major_axes        (n, 3)   float32   unit tangent along the field's major direction
spacings          (n, 2)   float32   expected spacing along the major and minor axis
segments          (n,)     uint32    segment of the sample's face
ranks             (n,)     uint32    rank of the sample in its sequence
================  =======  ========  =================================================
"""

from __future__ import annotations

import json
from typing import Any, Dict, Iterable, List, Optional, Sequence, Tuple, Union

import numpy as np

from ._strata import (
    Field,
    Sampler,
    Samples,
    load_mesh,
    radial_spectrum,
    star_discrepancy,
    surface_spectrum,
)

__all__ = [
    "Field",
    "Sampler",
    "Samples",
    "sample",
    "interpolate",
    "load_mesh",
    "star_discrepancy",
    "radial_spectrum",
    "surface_spectrum",
    "constant",
    "curvature",
    "designed",
    "isotropic",
    "frames",
    "tensors",
    "from_scene",
]

FieldLike = Union[None, Field, str, Dict[str, Any]]


def sample(
    vertices: Any,
    faces: Any,
    n: int,
    *,
    field: FieldLike = None,
    seed: int = 0,
    order: str = "stratified",
    options: Union[None, Dict[str, Any], str] = None,
    progress: Optional[bool] = None,
) -> Samples:
    """Samples ``n`` points on a triangle mesh, exactly ``n``, in one call.

    ``vertices`` is ``(V, 3)`` (float32, float64 or integers), ``faces`` ``(F, 3)``
    (any integer dtype), in C or Fortran order. ``field`` is ``None`` (uniform
    density), a ``Field``, a scene file's field description (RON text) or a dict of
    the same structure. ``order`` is ``"stratified"`` (exactly stratified for ``n``)
    or ``"progressive"`` (the first ``n`` of one sequence: fewer samples are a prefix
    of more). ``options`` are the preprocessing settings (see ``Sampler``). The same
    inputs and seed give the same samples, bit for bit, on any thread count.

    Raises ``ValueError`` with the engine's message for bad input.
    """
    return Sampler(vertices, faces, field, options=options, progress=progress).sample(
        n, seed=seed, order=order
    )


def interpolate(faces: Any, face_ids: Any, barycentrics: Any, vertex_values: Any) -> np.ndarray:
    """Interpolates per-vertex values (colours, UVs, any attribute) at samples.

    ``faces`` ``(F, 3)`` integers, ``face_ids`` ``(n,)``, ``barycentrics`` ``(n, 3)``
    (as in ``Samples``), ``vertex_values`` ``(V,)`` or ``(V, k)``. Returns ``(n,)`` or
    ``(n, k)`` in float64 (or the values' dtype when it is a wider float):
    ``sum_j barycentrics[:, j] * vertex_values[faces[face_ids, j]]``.
    """
    faces = np.asarray(faces)
    face_ids = np.asarray(face_ids)
    bary = np.asarray(barycentrics)
    values = np.asarray(vertex_values)
    if faces.ndim != 2 or faces.shape[1] != 3 or faces.dtype.kind not in "iu":
        raise ValueError(f"faces must be an integer array of shape (F, 3), got {faces.dtype} {faces.shape}")
    if face_ids.ndim != 1 or face_ids.dtype.kind not in "iu":
        raise ValueError(f"face_ids must be an integer array of shape (n,), got {face_ids.dtype} {face_ids.shape}")
    if bary.shape != (face_ids.shape[0], 3):
        raise ValueError(f"barycentrics must have shape ({face_ids.shape[0]}, 3), got {bary.shape}")
    if values.ndim not in (1, 2) or values.dtype.kind not in "fiub":
        raise ValueError(f"vertex_values must be numbers of shape (V,) or (V, k), got {values.dtype} {values.shape}")
    if face_ids.size and (face_ids.min() < 0 or face_ids.max() >= faces.shape[0]):
        raise ValueError(f"face_ids must be in 0..{faces.shape[0]}")
    if faces.size and (faces.min() < 0 or faces.max() >= values.shape[0]):
        raise ValueError(
            f"faces refer to vertices outside 0..{values.shape[0]} (vertex_values has {values.shape[0]} rows)"
        )
    dtype = np.result_type(values.dtype, np.float64)
    corners = faces[face_ids]  # (n, 3)
    w = bary.astype(dtype, copy=False)
    v = values.astype(dtype, copy=False)
    out: np.ndarray
    if v.ndim == 1:
        out = (v[corners] * w).sum(axis=1)
    else:
        out = np.einsum("nj,njk->nk", w, v[corners])
    return out


def _field(description: Dict[str, Any]) -> Field:
    try:
        text = json.dumps(description, allow_nan=False)
    except ValueError:
        raise ValueError(f"field values must be finite numbers: {description}") from None
    return Field.from_json(text)


def _vec3(name: str, v: Sequence[float]) -> List[float]:
    out = [float(x) for x in v]
    if len(out) != 3:
        raise ValueError(f"{name} must have 3 components, got {len(out)}")
    return out


def constant(
    direction: Sequence[float] = (1.0, 0.0, 0.0),
    anisotropy: float = 1.0,
    density: float = 1.0,
) -> Field:
    """A constant world direction projected into each tangent plane, with a constant
    spacing ratio ``anisotropy`` (>= 1: samples that many times closer along the
    direction) and density (> 0)."""
    return _field(
        {
            "Constant": {
                "direction": _vec3("direction", direction),
                "anisotropy": float(anisotropy),
                "density": float(density),
            }
        }
    )


def curvature(**options: Any) -> Field:
    """Density and anisotropy from the principal curvatures. Options (scene-file
    names and defaults): ``measure`` ("Rms", "Mean", "Gaussian" or "MaxAbs"),
    ``normalization``, ``floor`` (0.2), ``scale`` (1), ``max_anisotropy`` (4),
    ``isotropy_curvature`` (0.05), ``smoothing_iterations`` (2)."""
    return _field({"Curvature": options})


def _guidance(guidance: Union[str, Sequence[float], Dict[str, Any]], smoothing_iterations: Optional[int]) -> Any:
    if isinstance(guidance, dict):
        return guidance
    if isinstance(guidance, str):
        if guidance == "smoothest":
            return "Smoothest"
        if guidance == "curvature":
            opts = {} if smoothing_iterations is None else {"smoothing_iterations": int(smoothing_iterations)}
            return {"Curvature": opts}
        raise ValueError(f'guidance must be "curvature", "smoothest" or a direction, got {guidance!r}')
    return {"Direction": _vec3("guidance direction", guidance)}


def _constraint(c: Any) -> Dict[str, Any]:
    at, direction = c
    site: Dict[str, Any]
    if isinstance(at, (int, np.integer)):
        site = {"Vertex": int(at)}
    else:
        site = {"Point": _vec3("constraint point", at)}
    return {"at": site, "direction": _vec3("constraint direction", direction)}


def _source(value: Any) -> Any:
    if isinstance(value, (int, float, np.number)):
        return {"Constant": float(value)}
    return value


def designed(
    guidance: Union[str, Sequence[float], Dict[str, Any]] = "curvature",
    *,
    weight: float = 1.0,
    smoothness: float = 0.5,
    smoothing: float = 0.3,
    constraints: Iterable[Tuple[Any, Sequence[float]]] = (),
    anisotropy: Union[float, Dict[str, Any]] = 3.0,
    density: Union[float, Dict[str, Any]] = 1.0,
    solver: str = "Auto",
    cancel_distance: float = 0.5,
    smoothing_iterations: Optional[int] = None,
) -> Field:
    """A designed field: a smooth line field with few singularities aligned to a
    guidance and to hard constraints.

    ``guidance``: ``"curvature"`` (default), ``"smoothest"`` or a world direction
    ``(x, y, z)``. ``weight`` (>= 0) trades guidance against smoothness;
    ``constraints`` are ``(vertex_index_or_point, direction)`` pairs; ``anisotropy``
    and ``density`` are numbers (constant) or scene-file dicts such as
    ``{"Curvature": {"max": 4.0}}`` or ``{"Shading": {"light": [0, 0, 1]}}``.
    ``solver`` is ``"Auto"``, ``"Direct"`` or ``"Multigrid"``.
    """
    return _field(
        {
            "Designed": {
                "guidance": _guidance(guidance, smoothing_iterations),
                "weight": float(weight),
                "smoothness": float(smoothness),
                "smoothing": float(smoothing),
                "constraints": [_constraint(c) for c in constraints],
                "anisotropy": _source(anisotropy),
                "density": _source(density),
                "solver": solver,
                "cancel_distance": float(cancel_distance),
            }
        }
    )


def isotropic(densities: Any) -> Field:
    """An isotropic field with a density per vertex (``(V,)``, each finite and > 0)."""
    return Field.from_densities(densities)


def frames(directions: Any, eigenvalues: Any) -> Field:
    """Per vertex a major direction ``(V, 3)`` and eigenvalues ``(l1, l2)`` ``(V, 2)``
    (both > 0; spacing ratio ``sqrt(l1 / l2)``, density ``sqrt(l1 l2)``)."""
    return Field.from_frames(directions, eigenvalues)


def tensors(values: Any) -> Field:
    """Symmetric tensors per vertex, ``(V, 3, 3)``, positive definite in each vertex's
    tangent plane."""
    return Field.from_tensors(values)


def from_scene(description: str) -> Field:
    """A field from a scene file's ``field:`` description in RON, e.g.
    ``"Curvature(floor: 0.1, max_anisotropy: 3.0)"``: every scene option."""
    return Field.from_ron(description)
