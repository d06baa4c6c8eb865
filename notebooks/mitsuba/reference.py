"""Mitsuba 3 reference renders of mirage scene files.

Mitsuba has no continuously varying refractive index, so the reference is built
the faithful way: a custom integrator (:class:`CurvedRayIntegrator`, a
``mi.SamplingIntegrator``) bends each camera ray by RK4 through the same
logistic medium (the formulas of ``src/medium/logistic.rs``, read from the scene file), in
the same τ form as mirage (dx/dτ = v, dv/dτ = n∇n, v = n·t), and lets Mitsuba
intersect each straight chord between two steps with the scene. A ray that
escapes sees the environment map that ``mirage sky`` exported, along its final
direction. The scene (camera, ground, objects, sky) is built from the same file.

Albedo mode only: a hit shows the surface's diffuse reflectance, a miss the sky.

Two ways to sample pixels:

- ``sampling="mirage"`` (default): the rays through mirage's own sample points
  (pixel centre, then the R2 low-discrepancy sequence, the same offsets in every
  pixel), so that the two renders differ only where the geometry of the rays
  differs;
- ``sampling="mitsuba"``: ``mi.render`` with the perspective sensor, a box
  reconstruction filter and the independent sampler (random points in the pixel).

The stock check renders the scene with Mitsuba's own integrators and straight
rays: the ``aov`` integrator's albedo (surfaces; 0 for a miss) plus the ``path``
integrator with ``max_depth`` 1 (only emitters seen directly: the environment
for a miss, 0 on a surface, since no surface emits).

Facts this code relies on (Mitsuba 3.9.1, drjit 1.5.0):

- ``mi.Ray3f(o, d, x)`` sets the *time* to x: maxt is set with
  ``mi.Ray3f(mi.Ray3f(o, d), maxt)``;
- in the llvm variants, loop state holding literals must be made opaque;
- Mitsuba's ``look_at`` puts world +x on the image's left, and so does mirage
  (right = forward × up), so cameras map one to one;
- float32 is enough when the ray's v is carried directly (δ ~ 1e-4 is computed
  on its own, never as ``n − 1``).

Usage::

    python reference.py SCENE.json --sky sky.exr -o ref.exr [--width W --height H --spp N]
        [--stock] [--sampling mirage|mitsuba]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from pathlib import Path

import numpy as np

os.environ.setdefault("DRJIT_LIBLLVM_PATH", "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1")

import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402

C_SCALE = 0.003
DEFAULT_STEP = 4.0
DEFAULT_MAX_DISTANCE = 20_000.0
# Half size of the ground rectangle (metres): mirage's ground is the whole plane.
GROUND_HALF = 1.0e6


def set_variant() -> str:
    """Mitsuba's llvm_ad_rgb variant (it needs LLVM 19). The scalar variants
    would take hours with a Python integrator, and this code is written for
    wide arrays (one lane per camera sample), so there is no fallback."""
    try:
        mi.set_variant("llvm_ad_rgb")
    except Exception as e:  # noqa: BLE001 - a missing LLVM shows up as any error
        raise RuntimeError(
            "Mitsuba's llvm_ad_rgb variant is unavailable: it needs LLVM 19 "
            "(apt-get install libllvm19; DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1)"
            f": {e}"
        ) from e
    return mi.variant()


# The integrator class derives from a variant's class: choose the variant first.
VARIANT = set_variant()


class ExportError(ValueError):
    """A scene that cannot be built exactly in Mitsuba."""


# ---------------------------------------------------------------------------
# Scene files


def load_scene(path: str | Path) -> dict:
    """The scene file as a dict, with ``medium_from`` resolved to ``medium``."""
    path = Path(path)
    scene = json.loads(path.read_text())
    if "medium_from" in scene:
        other = json.loads((path.parent / scene["medium_from"]).read_text())
        scene["medium"] = other["medium"]
    return scene


# ---------------------------------------------------------------------------
# The medium, in drjit (the same formulas as src/medium/logistic.rs)


def _sigmoid(t):
    e = dr.exp(-dr.abs(t))
    return dr.select(t >= 0, 1.0 / (1.0 + e), e / (1.0 + e))


def _sigmoid_np(t):
    e = np.exp(-np.abs(t))
    return np.where(t >= 0, 1.0 / (1.0 + e), e / (1.0 + e))


class Medium:
    """δ(p) and ∇δ(p) of the logistic model, C·|k_s|·D(p)/S."""

    def __init__(self, m: dict | None, straight: bool = False):
        m = m or {}
        self.background = m.get("background")
        self.inversion = m.get("inversion")
        self.hotspots = [{"edge": 10.0, **h} for h in m.get("hotspots", [])]
        amps = []
        if self.background:
            amps.append(self.background["n"])
        if self.inversion:
            amps.append(self.inversion["n"])
        amps += [h["n"] for h in self.hotspots]
        s = sum(abs(a) for a in amps)
        self.k = 0.0 if (straight or s == 0) else C_SCALE * abs(m.get("scale", 1.0)) / s
        self.straight = self.k == 0.0
        # n_max: |D/S| ≤ 1.
        self.n_max = 1.0 + C_SCALE * abs(m.get("scale", 1.0)) if not self.straight else 1.0

    # -- stratified part, host side, float64 (for Snell decisions)
    def strat_delta_np(self, y):
        y = np.asarray(y, dtype=float)
        d = np.zeros_like(y)
        if self.background:
            b = self.background
            d += b["n"] * _sigmoid_np(y / b["a"])
        if self.inversion:
            i = self.inversion
            d += i["n"] * _sigmoid_np((i["height"] - y) / i["a"])
        return self.k * d

    def profile_top(self) -> float:
        """A height above which the stratified δ is constant to < e^-20 of each term."""
        top = 100.0
        if self.background:
            top = max(top, 20 * abs(self.background["a"]))
        if self.inversion:
            top = max(top, self.inversion["height"] + 20 * abs(self.inversion["a"]))
        return top

    def zone_top(self) -> float:
        """Height above which every hot spot has died out (0 without hot spots)."""
        top = 0.0
        for h in self.hotspots:
            top = max(top, 20 * abs(h["a"]) if h["a"] < 0 else math.inf)
        return top

    # -- full field, device side
    def delta_grad(self, p):
        """(δ, ∇δ) at points p (mi.Point3f)."""
        x, y, z = p.x, p.y, p.z
        zero = dr.zeros(mi.Float, dr.width(y))
        d = mi.Float(zero)
        gx, gy, gz = mi.Float(zero), mi.Float(zero), mi.Float(zero)
        if self.background:
            n, a = self.background["n"], self.background["a"]
            s = _sigmoid(y / a)
            d += n * s
            gy += n * s * (1 - s) / a
        if self.inversion:
            n, a, h = self.inversion["n"], self.inversion["a"], self.inversion["height"]
            s = _sigmoid((h - y) / a)
            d += n * s
            gy -= n * s * (1 - s) / a
        for hs in self.hotspots:
            n, a, e, r = hs["n"], hs["a"], hs["edge"], hs["radius"]
            dx, dz = x - hs["x"], z - hs["z"]
            rho = dr.sqrt(dx * dx + dz * dz)
            sr = _sigmoid(e * (rho - r))
            w = 1 - sr
            sy = _sigmoid(y / a)
            d += n * w * sy
            gy += n * w * sy * (1 - sy) / a
            # ∂w/∂ρ = −e·σ'(e(ρ − R)); at ρ = 0 the cone tip's derivative is 0.
            dw = -e * sr * (1 - sr)
            inv = dr.select(rho > 0, 1.0 / rho, 0.0)
            gx += n * sy * dw * dx * inv
            gz += n * sy * dw * dz * inv
        k = self.k
        return d * k, mi.Vector3f(gx * k, gy * k, gz * k)

    def rate(self, x):
        """dv/dτ = n∇n at x."""
        d, g = self.delta_grad(x)
        return g * (1.0 + d)


# ---------------------------------------------------------------------------
# Shapes: the SDF tree mapped to exact Mitsuba shapes


def _vec(v):
    return mi.ScalarVector3f(float(v[0]), float(v[1]), float(v[2]))


def shapes_of(sdf: dict, xf, where: str) -> list[dict]:
    """Mitsuba shape dicts (without BSDF) of an SDF, under the transform xf.

    Unions become several shapes (the first hit of a union is the first hit of
    any child); translate/rotate/scale compose into to_world. Shapes Mitsuba
    cannot represent exactly raise ExportError naming the field.
    """
    t = sdf.get("type")
    T = mi.ScalarTransform4f
    if t == "sphere":
        return [
            {
                "type": "sphere",
                "to_world": xf @ T().translate(_vec(sdf["center"])) @ T().scale(float(sdf["radius"])),
            }
        ]
    if t == "box":
        return [
            {
                "type": "cube",
                "to_world": xf @ T().translate(_vec(sdf["center"])) @ T().scale(_vec(sdf["half_extents"])),
            }
        ]
    if t == "cylinder":
        c, r, hh = sdf["center"], float(sdf["radius"]), float(sdf["half_height"])
        base = xf @ T().translate(_vec(c))
        # Mitsuba's cylinder runs along local z from 0 to 1 and is open: add two disks.
        to_y = T().rotate(mi.ScalarVector3f(1, 0, 0), -90.0)  # local +z → world +y
        return [
            {
                "type": "cylinder",
                "to_world": base @ T().translate(mi.ScalarVector3f(0, -hh, 0)) @ to_y @ T().scale(mi.ScalarVector3f(r, r, 2 * hh)),
            },
            {
                "type": "disk",
                "to_world": base @ T().translate(mi.ScalarVector3f(0, hh, 0)) @ to_y @ T().scale(mi.ScalarVector3f(r, r, 1)),
            },
            {
                "type": "disk",
                "to_world": base @ T().translate(mi.ScalarVector3f(0, -hh, 0)) @ T().rotate(mi.ScalarVector3f(1, 0, 0), 90.0) @ T().scale(mi.ScalarVector3f(r, r, 1)),
            },
        ]
    if t == "capsule":
        a, b, r = np.array(sdf["a"], float), np.array(sdf["b"], float), float(sdf["radius"])
        out = [
            {"type": "sphere", "to_world": xf @ T().translate(_vec(a)) @ T().scale(r)},
            {"type": "sphere", "to_world": xf @ T().translate(_vec(b)) @ T().scale(r)},
        ]
        if np.linalg.norm(b - a) > 0:
            # The transforms are rigid motions and uniform scales: the segment's
            # ends map exactly, and the radius scales by the transform's factor.
            factor = float(dr.norm(xf @ mi.ScalarVector3f(1, 0, 0)))
            out.append({"type": "cylinder", "p0": xf @ mi.ScalarPoint3f(*a),
                        "p1": xf @ mi.ScalarPoint3f(*b), "radius": r * factor})
        return out
    if t == "union":
        out = []
        for i, child in enumerate(sdf["children"]):
            out += shapes_of(child, xf, f"{where}.children[{i}]")
        return out
    if t == "translate":
        return shapes_of(sdf["child"], xf @ T().translate(_vec(sdf["offset"])), f"{where}.child")
    if t == "rotate":
        axis = np.array(sdf["axis"], float)
        axis /= np.linalg.norm(axis)  # Mitsuba's rotate expects a unit axis; mirage normalises
        return shapes_of(sdf["child"], xf @ T().rotate(_vec(axis), float(sdf["degrees"])), f"{where}.child")
    if t == "scale":
        return shapes_of(sdf["child"], xf @ T().scale(float(sdf["factor"])), f"{where}.child")
    _fail(where, f"shape type `{t}` has no exact Mitsuba counterpart "
          "(exportable: sphere, box, cylinder, capsule, union, translate, rotate, scale)")


def _fail(where, message):
    raise ExportError(f"{where}: {message}")


def objects_box(scene: dict) -> tuple[np.ndarray, np.ndarray] | None:
    """World bounding box of every exported object (None without objects)."""
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    for i, obj in enumerate(scene.get("objects", [])):
        for s in shapes_of(obj["shape"], mi.ScalarTransform4f(), f"objects[{i}].shape"):
            shape = mi.load_dict(s)
            bb = shape.bbox()
            lo = np.minimum(lo, np.array(bb.min))
            hi = np.maximum(hi, np.array(bb.max))
    return None if not np.all(np.isfinite(lo)) else (lo, hi)


def camera_dict(scene: dict, width: int, height: int, spp: int, seed: int = 0) -> dict:
    cam = scene["camera"]
    return {
        "type": "perspective",
        "fov_axis": "y",
        "fov": float(cam["vertical_fov"]),
        "near_clip": 0.01,
        "far_clip": 1.0e7,
        "to_world": mi.ScalarTransform4f().look_at(
            origin=cam["position"], target=cam["look_at"], up=cam.get("up", [0, 1, 0])
        ),
        "film": {
            "type": "hdrfilm",
            "width": width,
            "height": height,
            "pixel_format": "rgb",
            "rfilter": {"type": "box"},
        },
        "sampler": {"type": "independent", "sample_count": spp, "seed": seed},
    }


def image_size(scene: dict, width: int | None, height: int | None) -> tuple[int, int]:
    """The image size as mirage derives it from --width/--height overrides."""
    w0, h0 = scene["camera"]["width"], scene["camera"]["height"]
    if width and height:
        return width, height
    if width:
        return width, max(1, round(width * h0 / w0))
    if height:
        return max(1, round(height * w0 / h0)), height
    return w0, h0


def build_scene(scene: dict, sky_exr: str | Path, width: int, height: int, spp: int) -> mi.Scene:
    """The Mitsuba scene of a mirage scene: camera, ground, objects, sky."""
    d = {
        "type": "scene",
        "sensor": camera_dict(scene, width, height, spp),
        "sky": {"type": "envmap", "filename": str(sky_exr)},
    }
    ground = scene.get("ground")
    if ground is not None:
        if "albedo" not in ground:
            raise ExportError("ground: only a uniform `albedo` ground is exported (not `checker`)")
        T = mi.ScalarTransform4f
        d["ground"] = {
            "type": "rectangle",
            # Local xy plane (normal +z) → the plane y = 0, normal +y.
            "to_world": T().rotate(mi.ScalarVector3f(1, 0, 0), -90.0) @ T().scale(GROUND_HALF),
            "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": ground["albedo"]}},
        }
    for i, obj in enumerate(scene.get("objects", [])):
        bsdf = {"type": "diffuse", "reflectance": {"type": "rgb", "value": obj["albedo"]}}
        for j, s in enumerate(shapes_of(obj["shape"], mi.ScalarTransform4f(), f"objects[{i}].shape")):
            s["bsdf"] = bsdf
            d[f"object_{i}_{j}"] = s
    return mi.load_dict(d)


# ---------------------------------------------------------------------------
# The curved-ray integrator


class CurvedRayIntegrator(mi.SamplingIntegrator):
    """Albedo along rays bent by RK4 through the logistic medium; Mitsuba intersects the chords."""

    def __init__(self, scene: dict, props: mi.Properties | None = None, straight: bool = False):
        super().__init__(props or mi.Properties())
        self.medium = Medium(scene.get("medium"), straight=straight)
        trace = scene.get("trace", {})
        self.step = float(trace.get("step", DEFAULT_STEP))
        self.max_distance = float(trace.get("max_distance", DEFAULT_MAX_DISTANCE))
        box = objects_box(scene)
        # Above this height a rising ray outside the hot spots can meet nothing.
        self.clear_height = max(box[1][1] if box else 0.0, self.medium.zone_top(), 0.0)
        # Snell decisions: suffix minima of the stratified δ over height.
        top = self.medium.profile_top()
        self.dy = max(top / 4096.0, 0.01)
        ys = np.arange(0.0, top + self.dy, self.dy)
        delta = self.medium.strat_delta_np(ys)
        self.delta_top = float(delta[-1])
        self.suffix_min = mi.Float(np.minimum.accumulate(delta[::-1])[::-1].astype(np.float32))
        self.n_table = len(ys)

    def _rk4(self, x, v, h):
        m = self.medium
        k1x, k1v = v, m.rate(x)
        k2x, k2v = v + k1v * (0.5 * h), m.rate(x + k1x * (0.5 * h))
        k3x, k3v = v + k2v * (0.5 * h), m.rate(x + k2x * (0.5 * h))
        k4x, k4v = v + k3v * h, m.rate(x + k3x * h)
        x1 = mi.Point3f(x + (k1x + 2 * k2x + 2 * k3x + k4x) * (h / 6))
        v1 = v + (k1v + 2 * k2v + 2 * k3v + k4v) * (h / 6)
        return x1, v1

    def _escape(self, x, v):
        """(escapes, asymptotic direction) of a rising ray outside the hot spots.

        Snell: v_h is conserved, and at height y' the vertical part satisfies
        v_y'² = v_y² + (δ(y') − δ(y))(2 + δ(y') + δ(y)), computed from small
        numbers so that float32 keeps it. It escapes if that stays positive at
        every height above (the suffix minimum of δ); it then leaves along the
        direction it has where δ no longer changes (what mirage shows too).
        """
        m = self.medium
        idx = dr.clip(mi.UInt32(dr.floor(dr.maximum(x.y, 0.0) / self.dy)), 0, self.n_table - 1)
        mn = dr.gather(mi.Float, self.suffix_min, idx)
        d, _ = m.delta_grad(x)
        vy2_min = v.y * v.y + (mn - d) * (2 + mn + d)
        vy2_top = v.y * v.y + (self.delta_top - d) * (2 + self.delta_top + d)
        escapes = (v.y > 0) & (vy2_min > 0)
        final = dr.normalize(mi.Vector3f(v.x, dr.sqrt(dr.maximum(vy2_top, 0.0)), v.z))
        return escapes, final

    def trace(self, scene: mi.Scene, o, d, active):
        """Linear RGB seen along the curved rays from o along d: the albedo of
        the first surface a chord meets, else the sky along the final direction."""
        m = self.medium
        n = dr.width(o.x)
        d0, _ = m.delta_grad(o)
        v = mi.Vector3f(d * (1.0 + d0))
        h = self.step / m.n_max
        s = dr.zeros(mi.Float, n)
        result = dr.zeros(mi.Color3f, n)
        sky_dir = mi.Vector3f(d)
        alive = mi.Bool(active)
        hit_any = dr.zeros(mi.Bool, n)
        x = mi.Point3f(o)
        dr.make_opaque(s, result, sky_dir, alive, hit_any, x, v)
        straight = m.straight
        clear, max_distance = self.clear_height, self.max_distance

        def cond(x, v, s, alive, hit_any, result, sky_dir):
            return alive

        def body(x, v, s, alive, hit_any, result, sky_dir):
            if straight:
                x1, v1 = x + v * max_distance, v
            else:
                x1, v1 = self._rk4(x, v, h)
            chord = x1 - x
            length = dr.norm(chord)
            ray = mi.Ray3f(mi.Ray3f(x, chord / length), length)
            si = scene.ray_intersect(ray, alive)
            hit = alive & si.is_valid()
            bsdf = si.bsdf(mi.RayDifferential3f(ray))
            albedo = bsdf.eval_diffuse_reflectance(si, hit)
            result = dr.select(hit, albedo, result)
            hit_any = hit_any | hit
            alive = alive & ~hit
            s = s + length
            if straight:
                esc, final = alive, dr.normalize(v1)
            else:
                esc, final = self._escape(x1, v1)
                esc = alive & esc & (x1.y > clear)
            out = alive & (s >= max_distance)
            sky_dir = dr.select(esc, final, dr.select(out, dr.normalize(v1), sky_dir))
            alive = alive & ~esc & ~out
            return mi.Point3f(x1), mi.Vector3f(v1), s, alive, hit_any, result, sky_dir

        x, v, s, alive, hit_any, result, sky_dir = dr.while_loop(
            state=(x, v, s, alive, hit_any, result, sky_dir), cond=cond, body=body
        )
        miss = mi.Bool(active) & ~hit_any
        si = dr.zeros(mi.SurfaceInteraction3f, n)
        si.wi = -sky_dir
        sky = scene.environment().eval(si, miss)
        return dr.select(miss, mi.Color3f(sky), result)

    def sample(self, scene, sampler, ray, medium=None, active=True):
        active = mi.Bool(active)
        color = self.trace(scene, mi.Point3f(ray.o), mi.Vector3f(ray.d), active)
        return mi.Spectrum(color), active, []

    def aov_names(self):
        return []

    def to_string(self):
        return "CurvedRayIntegrator[]"


# ---------------------------------------------------------------------------
# Rendering


def r2_offsets(spp: int) -> np.ndarray:
    """mirage's sample offsets inside a pixel (src/render/camera.rs `sample_offset`)."""
    a1, a2 = 0.7548776662466927, 0.5698402909980533
    k = np.arange(spp, dtype=float)
    return np.stack([np.modf(0.5 + a1 * k)[0], np.modf(0.5 + a2 * k)[0]], axis=1)


def mirage_rays(scene: dict, width: int, height: int, spp: int) -> tuple[np.ndarray, np.ndarray]:
    """Origins and unit directions (float64) of mirage's camera rays, pixel-major."""
    cam = scene["camera"]
    pos = np.array(cam["position"], float)
    fwd = np.array(cam["look_at"], float) - pos
    fwd /= np.linalg.norm(fwd)
    right = np.cross(fwd, np.array(cam.get("up", [0, 1, 0]), float))
    right /= np.linalg.norm(right)
    up = np.cross(right, fwd)
    tan_half = math.tan(0.5 * math.radians(cam["vertical_fov"]))
    aspect = width / height
    off = r2_offsets(spp)
    jj, ii = np.meshgrid(np.arange(height), np.arange(width), indexing="ij")
    px = (ii[..., None] + off[:, 0]).reshape(-1)
    py = (jj[..., None] + off[:, 1]).reshape(-1)
    sx = (2 * px / width - 1) * tan_half * aspect
    sy = (1 - 2 * py / height) * tan_half
    d = fwd[None, :] + right[None, :] * sx[:, None] + up[None, :] * sy[:, None]
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return np.broadcast_to(pos, d.shape), d


def render_curved(scene: dict, sky_exr, width: int, height: int, spp: int,
                  sampling: str = "mirage", straight: bool = False) -> np.ndarray:
    """The custom integrator's image (H, W, 3) float32."""
    mscene = build_scene(scene, sky_exr, width, height, spp)
    integ = CurvedRayIntegrator(scene, straight=straight)
    if sampling == "mitsuba":
        return np.array(mi.render(mscene, integrator=integ, spp=spp))[..., :3]
    o, d = mirage_rays(scene, width, height, spp)
    out = np.zeros((width * height * spp, 3), np.float32)
    chunk = 1 << 20
    for a in range(0, len(d), chunk):
        b = min(a + chunk, len(d))
        oo = mi.Point3f(*[o[a:b, i].astype(np.float32) for i in range(3)])
        dd = mi.Vector3f(*[d[a:b, i].astype(np.float32) for i in range(3)])
        c = integ.trace(mscene, oo, dd, dr.ones(mi.Bool, b - a))
        out[a:b] = np.array(c).T if np.array(c).shape[0] == 3 else np.array(c)
    return out.reshape(height, width, spp, 3).mean(axis=2)


def render_stock(scene: dict, sky_exr, width: int, height: int, spp: int) -> np.ndarray:
    """Straight rays with Mitsuba's own integrators: aov albedo + path (max_depth 1)."""
    mscene = build_scene(scene, sky_exr, width, height, spp)
    albedo = mi.load_dict({"type": "aov", "aovs": "albedo:albedo"})
    direct = mi.load_dict({"type": "path", "max_depth": 1})
    a = np.array(mi.render(mscene, integrator=albedo, spp=spp, seed=1))
    e = np.array(mi.render(mscene, integrator=direct, spp=spp, seed=2))
    return (a[..., -3:] + e[..., :3]).astype(np.float32)


def write_exr(path, img: np.ndarray) -> None:
    mi.Bitmap(np.ascontiguousarray(img, dtype=np.float32)).write(str(path))


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("scene")
    p.add_argument("--sky", required=True, help="the scene's sky as exported by `mirage sky` (.exr)")
    p.add_argument("-o", "--output", required=True, help="output .exr (linear RGB)")
    p.add_argument("--width", type=int)
    p.add_argument("--height", type=int)
    p.add_argument("--spp", type=int, default=16)
    p.add_argument("--stock", action="store_true",
                   help="straight rays with Mitsuba's stock integrators (aov albedo + path max_depth 1)")
    p.add_argument("--straight", action="store_true", help="the custom integrator with δ ≡ 0")
    p.add_argument("--sampling", choices=["mirage", "mitsuba"], default="mirage")
    a = p.parse_args(argv)
    variant = mi.variant()
    scene = load_scene(a.scene)
    w, h = image_size(scene, a.width, a.height)
    try:
        if a.stock:
            img = render_stock(scene, a.sky, w, h, a.spp)
        else:
            img = render_curved(scene, a.sky, w, h, a.spp, a.sampling, a.straight)
    except ExportError as e:
        print(f"error: {a.scene}: {e}", file=sys.stderr)
        return 2
    write_exr(a.output, img)
    print(f"{a.output}: {w}×{h}, {a.spp} spp, {'stock' if a.stock else 'curved'} ({variant})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
