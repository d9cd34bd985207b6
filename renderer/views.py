"""Views, lights, materials and quality presets as plain data.

Every number here is in Parke's units and axes (X forward, Y to the face's left, Z up; the neck
base is near z = -594) and is the same for every subject, so images of different subjects,
versions and frames compare pixel for pixel. The four views are those of the thesis's evaluation
(section 5.1, Figure 5.1; rubric "Views"):

- ``front``: the full face from the starting orientation (camera on +X looking back);
- ``side``: the full head from its right side (camera on -Y), the face looking to image right;
- ``half``: the left half of the head, cut at the midsagittal plane y = 0 and seen from the cut
  side (camera on -Y), framed on the mouth so teeth, tongue and palate show;
- ``top``: looking down onto the palate (camera on +Z, front of the mouth at the image top); the
  skull above the palate is hidden (triangles above the palate's highest point plus a margin are
  left out of that view's scene) so the palate, teeth and tongue show.

Lights are defined in each camera's own frame (right, up, back) so every view gets the same soft
three-point studio set-up: a large key light up and to the camera's left, a weaker fill on the
right, a rim light from behind, and a dim constant environment for the shadows.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from cassi.common.errors import CassiInputError

__all__ = ["Camera", "Light", "View", "Preset", "Material", "VIEWS", "PRESETS", "MATERIALS",
           "DEFAULT_MATERIAL", "material_for", "mouth_box", "project", "view", "preset", "VIEW_NAMES", "PRESET_NAMES"]

Vec3 = tuple[float, float, float]


@dataclass(frozen=True)
class Camera:
    """A perspective pinhole camera.

    ``origin``/``target``/``up`` in Parke units; ``fov`` the vertical field of view in degrees
    (the films are square, so it is also the horizontal one).
    """

    origin: Vec3
    target: Vec3
    up: Vec3
    fov: float
    near_clip: float = 10.0
    far_clip: float = 100000.0

    def basis(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Unit vectors (right, up, back) of the camera in world space.

        Mitsuba's ``look_at`` maps the image's +x to ``cross(up, direction)`` (its cameras
        look along local +z with +x to the image *left*); ``right`` here is the image right.
        """
        o, t, u = (np.asarray(v, float) for v in (self.origin, self.target, self.up))
        d = t - o
        d /= np.linalg.norm(d)
        right = np.cross(d, u)
        right /= np.linalg.norm(right)
        up = np.cross(right, d)
        return right, up, -d

    @property
    def distance(self) -> float:
        return float(np.linalg.norm(np.subtract(self.target, self.origin)))


@dataclass(frozen=True)
class Light:
    """A rectangular area light placed in the camera's frame.

    ``offset`` = (right, up, back) multiples of the camera distance from the camera target;
    the light faces the target; ``size`` its side length as a fraction of the camera distance;
    ``radiance`` linear RGB.
    """

    name: str
    offset: Vec3
    size: float
    radiance: Vec3


@dataclass(frozen=True)
class View:
    name: str
    camera: Camera
    half: bool = False
    #: Hide geometry whose triangle centroid lies higher than the palate's top plus this margin
    #: (Parke units); None = show everything.
    clip_above_palate: float | None = None
    lights: tuple[Light, ...] = ()
    ambient: float = 0.18
    description: str = ""


@dataclass(frozen=True)
class Preset:
    """Film and sampling; fixed per preset so Dr.Jit kernels are compiled once and reused.

    ``shading``: ``"raycast"`` shades the colour from the one ``aov`` pass that also gives the
    mask and depth (one ray through each pixel centre: noise-free and bit-reproducible, see
    :mod:`cassi.renderer.shading`); ``"path"`` path-traces it with ``spp`` samples per pixel and
    ``seed``. ``look`` (raycast only): ``"smooth"`` interpolated vertex normals (Phong) or
    ``"flat"`` one normal per triangle, like the thesis's SGI display.
    """

    name: str
    width: int
    height: int
    spp: int
    seed: int
    max_depth: int
    rfilter: str = "gaussian"
    shading: str = "path"
    look: str = "smooth"

    def __post_init__(self):
        if self.shading not in ("raycast", "path"):
            raise ValueError(f"preset {self.name!r}: shading must be 'raycast' or 'path'")
        if self.look not in ("smooth", "flat"):
            raise ValueError(f"preset {self.name!r}: look must be 'smooth' or 'flat'")


# Where the neutral face sits (Parke units): used only to place the fixed cameras.
_FACE_CENTER = (40.0, 0.0, -50.0)
_MOUTH = (300.0, 0.0, -290.0)
_PALATE = (230.0, 0.0, -230.0)


def _camera(target: Vec3, direction: Vec3, up: Vec3, frame: float, fov: float = 22.0,
            near_clip: float = 10.0) -> Camera:
    """A camera looking at ``target`` from ``direction`` framing ``frame`` units vertically."""
    dist = 0.5 * frame / math.tan(math.radians(fov) / 2.0)
    d = np.asarray(direction, float)
    d /= np.linalg.norm(d)
    origin = tuple(float(x) for x in np.asarray(target) + dist * d)
    return Camera(origin=origin, target=target, up=up, fov=fov, near_clip=near_clip)


_STUDIO = (
    Light("key", offset=(-0.55, 0.45, 0.75), size=0.55, radiance=(5.5, 5.3, 5.0)),
    Light("fill", offset=(0.75, 0.10, 0.60), size=0.65, radiance=(1.6, 1.65, 1.75)),
    Light("rim", offset=(0.25, 0.70, -0.70), size=0.40, radiance=(2.0, 2.0, 2.0)),
)

VIEWS: dict[str, View] = {
    "front": View("front", _camera(_FACE_CENTER, (1, 0, 0), (0, 0, 1), frame=1230.0),
                  lights=_STUDIO, description="full face from the starting orientation"),
    "side": View("side", _camera(_FACE_CENTER, (0, -1, 0), (0, 0, 1), frame=1230.0),
                 lights=_STUDIO, description="full head from its right side, face to image right"),
    "half": View("half", _camera(_MOUTH, (0, -1, 0), (0, 0, 1), frame=700.0), half=True,
                 lights=_STUDIO, ambient=0.30,
                 description="left half cut at y = 0, seen from the cut side, framed on the mouth"),
    "top": View("top", _camera(_PALATE, (0, 0, 1), (1, 0, 0), frame=540.0),
                clip_above_palate=25.0, lights=_STUDIO, ambient=0.30,
                description="looking down onto the palate, skull above the palate hidden"),
}
VIEW_NAMES = tuple(VIEWS)

PRESETS: dict[str, Preset] = {
    # One primary ray per pixel (spp 1, no seed needed): colour, mask and depth from one pass.
    "preview": Preset("preview", 256, 256, spp=1, seed=0, max_depth=1, shading="raycast"),
    "flat": Preset("flat", 256, 256, spp=1, seed=0, max_depth=1, shading="raycast", look="flat"),
    "final": Preset("final", 512, 512, spp=64, seed=1, max_depth=4),
}
PRESET_NAMES = tuple(PRESETS)


@dataclass(frozen=True)
class Material:
    """A part's surface, one description for both shading modes.

    ``rgb`` diffuse reflectance (linear RGB); ``alpha`` GGX roughness; ``specular`` the weight of
    the glossy coat (0 = purely diffuse). The path tracer gets a two-sided rough plastic (diffuse
    base + dielectric coat: skin-like sheen without subsurface cost; two-sided so the inside of
    the cut head in the half view is shaded, not black), or a diffuse BSDF when ``specular`` is
    0; the raycast preview gets Lambert + a Blinn-Phong lobe of the same roughness.
    """

    rgb: Vec3
    alpha: float = 0.4
    specular: float = 0.0

    def bsdf(self) -> dict:
        """The Mitsuba BSDF dictionary of the path-traced presets."""
        if self.specular <= 0.0:
            inner = {"type": "diffuse", "reflectance": {"type": "rgb", "value": list(self.rgb)}}
        else:
            inner = {"type": "roughplastic", "distribution": "ggx", "alpha": self.alpha,
                     "diffuse_reflectance": {"type": "rgb", "value": list(self.rgb)},
                     "specular_reflectance": {"type": "rgb", "value": [self.specular] * 3}}
        return {"type": "twosided", "material": inner}

    @property
    def shininess(self) -> float:
        """Blinn-Phong exponent with the highlight width of GGX roughness ``alpha``
        (the usual correspondence n = 2 / alpha^2 - 2)."""
        return max(1.0, 2.0 / self.alpha ** 2 - 2.0)


#: Materials per part name (the part names of cassi.data.face.model.RenderTopology); linear RGB.
MATERIALS: dict[str, Material] = {
    "skin": Material((0.62, 0.42, 0.33), alpha=0.45, specular=0.35),
    "lips": Material((0.55, 0.22, 0.22), alpha=0.30, specular=0.5),
    "teeth": Material((0.85, 0.83, 0.74), alpha=0.12, specular=0.8),
    "tongue": Material((0.62, 0.20, 0.22), alpha=0.25, specular=0.6),
    "palate": Material((0.70, 0.35, 0.36), alpha=0.30, specular=0.5),
    "eye_white": Material((0.85, 0.84, 0.80), alpha=0.08, specular=1.0),
    "iris": Material((0.18, 0.28, 0.42), alpha=0.08, specular=1.0),
    "fringe": Material((0.10, 0.12, 0.16), alpha=0.08, specular=1.0),
    "pupil": Material((0.015, 0.015, 0.015), alpha=0.05, specular=1.0),
    "reflection": Material((0.95, 0.95, 0.95)),
    "eyelash": Material((0.05, 0.035, 0.03)),
    "eyebrow": Material((0.12, 0.08, 0.06)),
    "eyelid": Material((0.60, 0.40, 0.32), alpha=0.45, specular=0.35),
}
DEFAULT_MATERIAL = Material((0.5, 0.5, 0.5), alpha=0.4, specular=0.3)


def material_for(part: str) -> Material:
    """The material of a part: exact name, else the longest material name the part starts
    with (``teeth_upper`` -> ``teeth``), else a neutral grey."""
    if part in MATERIALS:
        return MATERIALS[part]
    prefixes = [m for m in MATERIALS if part.startswith(m)]
    if prefixes:
        return MATERIALS[max(prefixes, key=len)]
    return DEFAULT_MATERIAL


#: The mouth region the image gates look at: a box around the mouth (lips, teeth, front of the
#: tongue and palate), centre and half extents in Parke units (140 units = 35 mm).
MOUTH_CENTER = (270.0, 0.0, -265.0)
MOUTH_HALF_EXTENT = (140.0, 120.0, 110.0)


def project(view: View, preset: Preset, points) -> np.ndarray:
    """float (N, 2) pixel coordinates (column, row; 0 = the left/top edge) of world ``points``
    (N, 3) in ``view``'s camera at ``preset``'s film size."""
    right, up, back = view.camera.basis()
    d = np.asarray(points, float) - np.asarray(view.camera.origin, float)
    z = -(d @ back)
    tan = math.tan(math.radians(view.camera.fov) / 2.0)
    x = (d @ right) / (z * tan * preset.width / preset.height)
    y = (d @ up) / (z * tan)
    return np.stack([(x + 1) / 2 * preset.width, (1 - y) / 2 * preset.height], axis=1)


def mouth_box(view: View, preset: Preset) -> tuple[int, int, int, int]:
    """(row0, row1, col0, col1), end-exclusive: the image rectangle of the mouth region
    (the projected MOUTH box, clipped to the film). The same for every subject and frame."""
    c, e = np.asarray(MOUTH_CENTER, float), np.asarray(MOUTH_HALF_EXTENT, float)
    corners = c + e * np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
    px = project(view, preset, corners)
    col0, row0 = np.floor(px.min(axis=0)).astype(int)
    col1, row1 = np.ceil(px.max(axis=0)).astype(int)
    return (int(max(0, row0)), int(min(preset.height, row1)),
            int(max(0, col0)), int(min(preset.width, col1)))


def view(name: str) -> View:
    try:
        return VIEWS[name]
    except KeyError:
        raise CassiInputError(f"unknown view {name!r}; choose one of {', '.join(VIEWS)}") from None


def preset(name: str) -> Preset:
    try:
        return PRESETS[name]
    except KeyError:
        raise CassiInputError(f"unknown preset {name!r}; choose one of {', '.join(PRESETS)}") from None
