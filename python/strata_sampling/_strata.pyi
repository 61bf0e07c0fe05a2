"""Type stubs of the compiled module `strata_sampling._strata`."""

from os import PathLike
from typing import Any, Dict, List, Optional, Tuple, Union

import numpy as np
import numpy.typing as npt

FieldArg = Union[None, "Field", str, Dict[str, Any]]
OptionsArg = Union[None, Dict[str, Any], str]

class Field:
    """A tensor field, built for a mesh when a `Sampler` preprocesses it."""

    @staticmethod
    def from_ron(text: str) -> Field:
        """A field from a scene file's `field:` description in RON."""
    @staticmethod
    def from_json(text: str) -> Field:
        """A field from the same description as JSON."""
    @staticmethod
    def from_densities(densities: npt.ArrayLike) -> Field:
        """Isotropic, with a density per vertex, shape (V,)."""
    @staticmethod
    def from_frames(directions: npt.ArrayLike, eigenvalues: npt.ArrayLike) -> Field:
        """Per vertex a major direction (V, 3) and eigenvalues (l1, l2) (V, 2)."""
    @staticmethod
    def from_tensors(tensors: npt.ArrayLike) -> Field:
        """Symmetric tensors per vertex, shape (V, 3, 3)."""

class Samples:
    """Drawn samples, one numpy array per attribute (handed over without a copy)."""

    positions: npt.NDArray[np.float32]
    """(n, 3) world positions."""
    normals: npt.NDArray[np.float32]
    """(n, 3) unit normals (interpolated vertex normals)."""
    face_ids: npt.NDArray[np.uint32]
    """(n,) face of each sample."""
    barycentrics: npt.NDArray[np.float32]
    """(n, 3) weights of the face's corners 0, 1, 2."""
    major_axes: npt.NDArray[np.float32]
    """(n, 3) unit tangent along the field's major direction."""
    spacings: npt.NDArray[np.float32]
    """(n, 2) expected spacing along the major and the minor axis."""
    segments: npt.NDArray[np.uint32]
    """(n,) segment of each sample's face."""
    ranks: npt.NDArray[np.uint32]
    """(n,) rank of each sample in its sequence."""
    def __len__(self) -> int: ...

class Sampler:
    """A mesh and field preprocessed once; draws any number of samples."""

    def __init__(
        self,
        vertices: npt.ArrayLike,
        faces: npt.ArrayLike,
        field: FieldArg = None,
        *,
        options: OptionsArg = None,
        progress: Optional[bool] = None,
    ) -> None:
        """Preprocesses (GIL released; Ctrl-C raises KeyboardInterrupt). `options`:
        the engine's preprocessing settings (`segment`, `param`, `curve`,
        `min_segment_faces`, `angle_criterion`, `isotropy_threshold`, `chart_angle`,
        `merge_pieces`) as a dict or RON text. `progress`: a progress line on standard
        error for builds over a second (default: when standard error is a terminal)."""
    def sample(self, n: int, seed: int = 0, order: str = "stratified") -> Samples:
        """Draws exactly `n` samples; `order` is "stratified" or "progressive"."""
    def sample_into(self, out: Samples, seed: int = 0, order: str = "stratified") -> None:
        """Draws len(out) samples into out's arrays in place (no allocation): the
        values of sample(len(out), seed, order)."""
    @property
    def segments(self) -> int:
        """Final segments of the preprocessing."""
    @property
    def singularities(self) -> int:
        """Singular faces of the field the segmentation worked with."""
    @property
    def path(self) -> str:
        """"planar" (a flat mesh, one linear map) or "surface"."""
    @property
    def splits(self) -> int:
        """Invalid segments split during parameterization."""
    @property
    def merges(self) -> int:
        """Valid neighbouring pieces merged back."""
    @property
    def cells(self) -> int:
        """Adaptive Hilbert cells over all segments."""
    @property
    def stage_times(self) -> Dict[str, float]:
        """Seconds per preprocessing stage, in order."""
    @property
    def vertex_count(self) -> int:
        """Vertices of the preprocessed mesh."""
    @property
    def face_count(self) -> int:
        """Faces of the preprocessed mesh."""

def load_mesh(
    path: Union[str, PathLike[str]],
) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.uint32]]:
    """Reads an OBJ or PLY mesh: vertices (V, 3) float64, faces (F, 3) uint32."""

def star_discrepancy(points: npt.ArrayLike, kind: str = "l2") -> float:
    """Star discrepancy ("l2" or "sup") of points (N, 2) in the unit square."""

def radial_spectrum(
    point_sets: Union[npt.ArrayLike, List[npt.ArrayLike]],
    max_frequency: float = 2.0,
) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """(frequency, power, anisotropy_db) per annulus of the radially averaged
    power spectrum of point sets (each (N, 2)) in the unit square."""

def surface_spectrum(
    positions: npt.ArrayLike,
    normals: npt.ArrayLike,
    spacing: float,
    *,
    epsilon: float = 10.0,
    max_frequency: float = 2.5,
) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """(frequency, power, anisotropy_db) per annulus of the differential-domain
    spectrum of points (N, 3) with unit normals (N, 3) on a surface of uniform
    density, differences measured in units of ``spacing`` (``sqrt(area / N)``) within
    ``epsilon`` spacings. Blue noise has little power below frequency 1."""
