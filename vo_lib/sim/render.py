"""A rectified stereo pair rendered from a :class:`~vo_lib.sim.world.World`.

Every surface is a textured planar quad. Texels map to pixels by one homography,
``H = K [R^T e1, R^T e2, R^T (O - c)]``, so ``warpPerspective`` draws a quad over its screen box in
one call, from the mipmap level of its texel footprint (far surfaces do not alias). Visibility is a
z-buffer of *inverse* depth, affine in the pixel coordinates on a plane:
``1/z = n . K^-1 [u, v, 1] / (n . O_c)`` (:mod:`vo_lib.sim.composite`); truth depth comes from it.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, fields

import cv2
import numpy as np

from vo_lib.camera import StereoCamera
from vo_lib.geometry import yaw_matrix
from vo_lib.sim.composite import draw_nearer
from vo_lib.sim.textures import cached_surface
from vo_lib.sim.world import Patch, Segment, World, box

#: Nearest depth drawn, metres.
NEAR_PLANE = 0.05
#: Longest side of a quad, in texels: longer surfaces are cut into tiles, each textured at the
#: level of its own distance.
TILE_TEXELS = 300
#: Direction the light comes from (world frame) for the flat shading of walls.
LIGHT_DIRECTION = np.array([0.5, 0.3, 0.8]) / np.linalg.norm([0.5, 0.3, 0.8])
#: Grey level of the empty background (sky), top and bottom of the image.
SKY_GREY = (205, 180)
#: Texel size of the moving boxes' textures, metres.
MOVER_TEXEL = 0.02


@dataclass(frozen=True)
class _Quads:
    """Textured planar quads, as arrays over the quads."""

    corners: np.ndarray  # (Q, 4, 3) world corners, in order
    origin: np.ndarray  # (Q, 3) world point of texel (0, 0)
    e1: np.ndarray  # (Q, 3) world step of one texel along the texture's columns
    e2: np.ndarray  # (Q, 3) world step of one texel along the texture's rows
    normal: np.ndarray  # (Q, 3)
    shade: np.ndarray  # (Q,)
    textures: tuple  # each quad's mipmaps

    @staticmethod
    def join(parts) -> _Quads:
        arrays = [np.concatenate([getattr(p, f.name) for p in parts]) for f in fields(_Quads)[:-1]]
        return _Quads(*arrays, tuple(itertools.chain.from_iterable(p.textures for p in parts)))


@dataclass
class SensorEffects:
    """Imperfections of a real camera, applied after rendering."""

    noise_sigma: float = 0.0  #: standard deviation of additive Gaussian noise, grey levels
    exposure_gain: float = 1.0  #: multiplies every grey level (auto-exposure)
    blur_px: float = 0.0  #: length of a horizontal motion-blur kernel, pixels (0: none)

    def apply(self, image: np.ndarray, rng: np.random.Generator | None) -> np.ndarray:
        out = image
        if self.blur_px >= 1.0:
            out = cv2.blur(out, (int(round(self.blur_px)), 1))
        if self.exposure_gain != 1.0 or self.noise_sigma > 0:
            f = out.astype(np.float32) * self.exposure_gain
            if self.noise_sigma > 0:
                if rng is None:
                    raise ValueError("sensor noise needs an rng (numpy.random.Generator)")
                f += rng.normal(0.0, self.noise_sigma, f.shape).astype(np.float32)
            out = np.clip(f + 0.5, 0, 255).astype(np.uint8)
        return out


def _tiles(length: float, texel: float) -> np.ndarray:
    n = max(1, int(np.ceil(length / (TILE_TEXELS * texel) - 1e-9)))
    return np.linspace(0.0, length, n + 1)


def _shade(normal: np.ndarray) -> float:
    return float(0.7 + 0.3 * abs(normal @ LIGHT_DIRECTION))


def build_quads(world: World) -> _Quads:
    """Cut the world's segments, floor, ceiling and patches into textured quads."""
    texel = world.floor_texel
    quads = []
    for seg in world.segments:
        quads.append(_wall_quads(seg, seg.texel or texel, seg.texture_seed + 1000 * world.seed))
    xmin, xmax, ymin, ymax = world.floor_extent
    planes = [(0.0, world.seed * 7 + 1, 0.95, world.floor_style)]
    if world.ceiling_height is not None:
        planes.append((world.ceiling_height, world.seed * 7 + 2, 0.8, world.ceiling_style))
    for z, seed, shade, style in planes:
        plane = Patch(
            (xmin, ymin, z), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), xmax - xmin, ymax - ymin, style, seed
        )
        quads.append(_patch_quads(plane, texel, shade))
    quads += [_patch_quads(patch, texel) for patch in world.patches]
    return _Quads.join(quads)


def _patch_quads(patch, texel: float, shade: float | None = None, split_across: bool = True) -> _Quads:
    """Quads of a :class:`~vo_lib.sim.world.Patch` in tiles of at most TILE_TEXELS (along only, for
    a wall); ``shade`` overrides the flat shading of its normal."""
    along, across, origin = (np.asarray(v, float) for v in (patch.along, patch.across, patch.origin))
    total = max(patch.texture_length, patch.offset + patch.length)
    cols, rows = int(np.ceil(total / texel)) + 1, int(np.ceil(patch.width / texel)) + 1
    tex = cached_surface(patch.style, rows, cols, texel, patch.texture_seed)
    normal = np.cross(along, across)
    normal /= np.linalg.norm(normal)
    shade = _shade(normal) if shade is None else shade
    e1, e2, tex_origin = along * texel, across * texel, origin - patch.offset * along
    if patch.outline:
        corners = np.asarray([patch.outline], float)
    else:
        a = _tiles(patch.length, texel)
        b = _tiles(patch.width, texel) if split_across else np.array([0.0, patch.width])
        corners = np.array(
            [
                origin + np.array([[a0, b0], [a1, b0], [a1, b1], [a0, b1]]) @ np.stack([along, across])
                for a0, a1 in zip(a[:-1], a[1:], strict=True)
                for b0, b1 in zip(b[:-1], b[1:], strict=True)
            ]
        )
    q = len(corners)
    vectors = (np.tile(v, (q, 1)) for v in (tex_origin, e1, e2, normal))
    return _Quads(corners, *vectors, np.full(q, shade), (tex,) * q)


def _wall_quads(seg: Segment, texel: float, seed: int) -> _Quads:
    """Quads of a vertical :class:`~vo_lib.sim.world.Segment` (texture ``seed``), cut along it only."""
    (ax, ay), (bx, by) = seg.start, seg.end
    along = ((bx - ax) / seg.length, (by - ay) / seg.length, 0.0)
    wall = Patch((ax, ay, 0.0), along, (0.0, 0.0, 1.0), seg.length, seg.height, seg.style, seed)
    return _patch_quads(wall, texel, split_across=False)


def _mover_quads(mover) -> _Quads:
    """Four sides and the top of a :class:`~vo_lib.sim.world.Mover` in its body frame (x forward,
    y left, z up, origin at the bottom centre)."""
    sides = box((0.0, 0.0), mover.size, 0.0, mover.height, mover.texture_seed, style=mover.style)
    hl, hw, h = mover.size[0] / 2, mover.size[1] / 2, mover.height
    top = Patch(
        (-hl, hw, h), (1.0, 0.0, 0.0), (0.0, -1.0, 0.0), 2 * hl, 2 * hw, "plain", mover.texture_seed + 4
    )
    return _Quads.join(
        [*(_wall_quads(s, MOVER_TEXEL, s.texture_seed) for s in sides), _patch_quads(top, MOVER_TEXEL)]
    )


def _moved(quads: _Quads, t: np.ndarray, yaw: float) -> _Quads:
    """Body-frame quads carried to the world: turned by ``yaw``, moved by ``t``."""
    R = yaw_matrix(yaw)
    e1, e2, normal, origin = (
        np.array([R @ v for v in vs]) for vs in (quads.e1, quads.e2, quads.normal, quads.origin)
    )
    shade = np.array([_shade(n) for n in normal])
    return _Quads(quads.corners @ R.T + t, origin + t, e1, e2, normal, shade, quads.textures)


def _clip_near(points: np.ndarray, near: float) -> np.ndarray:
    """Sutherland-Hodgman clipping of a convex polygon (camera frame) to ``z >= near``."""
    out = []
    for p, q in zip(points, np.roll(points, -1, axis=0), strict=True):
        p_in, q_in = p[2] >= near, q[2] >= near
        if p_in:
            out.append(p)
        if p_in != q_in:
            t = (near - p[2]) / (q[2] - p[2])
            out.append(p + t * (q - p))
    return np.array(out).reshape(-1, 3)


def _draw(image, inv_depth, order, boxes, H, level, textures, shades, pts4, clipped, abe) -> None:
    """Warp each quad of ``order`` into its screen box and draw it where it is nearer (z-buffer)."""
    for i in order:
        x0, y0, x1, y1 = boxes[i]
        warped = cv2.warpPerspective(
            textures[i][level[i]],
            H[i],
            (x1 - x0, y1 - y0),
            flags=cv2.INTER_LINEAR,
            borderMode=cv2.BORDER_REPLICATE,
        )
        mask = np.zeros((y1 - y0, x1 - x0), np.uint8)
        pts = pts4[i] if i not in clipped else np.round((clipped[i] - (x0, y0)) * 16).astype(np.int32)
        cv2.fillConvexPoly(mask, pts, 1, lineType=cv2.LINE_8, shift=4)
        draw_nearer(image, inv_depth, warped, mask, x0, y0, *abe[i], shades[i])


class StereoRenderer:
    """Render rectified stereo pairs of a world (camera with ``width`` and ``height``), with truth
    depth on request."""

    def __init__(self, world: World, camera: StereoCamera, effects: SensorEffects | None = None):
        if camera.width is None or camera.height is None:
            raise ValueError("the renderer needs a camera with width and height")
        self.camera = camera
        self.effects = effects or SensorEffects()
        self.quads = build_quads(world)
        self._movers = [(m, _mover_quads(m)) for m in world.movers]
        w, h = camera.width, camera.height
        sky = np.linspace(SKY_GREY[0], SKY_GREY[1], h, dtype=np.float32)
        self._sky = np.repeat(sky[:, None], w, axis=1).astype(np.uint8)
        self._Kinv = np.linalg.inv(camera.K)
        # inward normals of the four side planes of the view frustum (through the optical centre)
        fx, fy, cx, cy = camera.fx, camera.fy, camera.cx, camera.cy
        self._frustum = np.array(
            [[fx, 0, cx + 0.5], [-fx, 0, w - 0.5 - cx], [0, fy, cy + 0.5], [0, -fy, h - 0.5 - cy]]
        )

    def render(self, T_world_camera, with_depth: bool = False, time: float = 0.0):
        """Grey image (uint8) seen by a camera at ``T_world_camera`` (4x4, camera to world), the
        movers where they are at ``time`` (seconds); or ``(image, depth)``, depth in metres (``inf``
        where nothing is)."""
        T = np.asarray(T_world_camera, dtype=float)
        R, c = T[:3, :3], T[:3, 3]
        cam = self.camera
        image = self._sky.copy()
        inv_depth = np.zeros(image.shape, np.float32)
        moving = [_moved(body, *mover.pose(time)) for mover, body in self._movers]  # at ``time``
        quads = _Quads.join([self.quads, *moving]) if moving else self.quads
        corners_c = (quads.corners - c) @ R  # (Q, 4, 3), camera frame
        # a quad is culled when all its corners lie outside one plane of the frustum
        outside = (corners_c @ self._frustum.T < 0).all(axis=1).any(axis=1)
        outside |= corners_c[..., 2].max(axis=1) <= NEAR_PLANE
        todo = np.flatnonzero(~outside)
        # all per-quad numbers at once; only drawing loops. Quads crossing the near plane: one by one
        cc = corners_c[todo]
        f, pp = np.array([cam.fx, cam.fy]), np.array([cam.cx, cam.cy])
        with np.errstate(divide="ignore", invalid="ignore"):
            uv4 = (cc[..., :2] / cc[..., 2:3]) * f + pp  # (N, 4, 2) pixel corners
        lo, hi = uv4.min(axis=1), uv4.max(axis=1)
        z_near = np.maximum(cc[..., 2].min(axis=1), NEAR_PLANE)
        clipped = {}
        for i in np.flatnonzero(cc[:, :, 2].min(axis=1) < NEAR_PLANE):
            poly = _clip_near(cc[i], NEAR_PLANE)
            uv = (poly[:, :2] / poly[:, 2:3]) * f + pp if len(poly) >= 3 else np.full((1, 2), np.nan)
            clipped[i] = uv
            lo[i], hi[i] = uv.min(axis=0), uv.max(axis=0)
        ok = np.isfinite(lo).all(axis=1)
        lo, hi = np.where(ok[:, None], lo, 0), np.where(ok[:, None], hi, -1)
        x0y0 = np.maximum(np.floor(lo).astype(int), 0)
        x1y1 = np.minimum(np.ceil(hi).astype(int) + 1, (cam.width, cam.height))
        # corners in 1/16 pixel from the box's corner, for fillConvexPoly (clipped quads: below)
        with np.errstate(invalid="ignore", over="ignore"):
            pts4 = np.round((uv4 - x0y0[:, None, :]) * 16).astype(np.int32)
        # texel -> pixel homography of each quad's plane: K [R^T e1, R^T e2, R^T (O - c)]
        e1_c, e2_c, o_c = quads.e1[todo] @ R, quads.e2[todo] @ R, (quads.origin[todo] - c) @ R
        H = cam.K @ np.stack([e1_c, e2_c, o_c], axis=2)  # (N, 3, 3)
        # texture level from the texel footprint at the nearest visible depth
        seen = [quads.textures[i] for i in todo]
        levels = np.array([len(mipmaps) for mipmaps in seen], int)
        pixels_per_texel = cam.fx * np.linalg.norm(quads.e1[todo], axis=1) / z_near
        with np.errstate(divide="ignore"):
            level = np.clip(np.floor(np.log2(1.0 / pixels_per_texel)), 0, levels - 1).astype(int)
        # cv2.pyrDown centres level-L texel (s, t) on base texel (2^L s, 2^L t)
        H[:, :, :2] *= (2.0**level)[:, None, None]
        # inverse depth on each plane, affine in (u, v): n . K^-1 [u, v, 1] / (n . O_c)
        n_c = quads.normal[todo] @ R
        dist = np.einsum("ij,ij->i", n_c, o_c)
        with np.errstate(divide="ignore", invalid="ignore"):
            abe = (n_c @ self._Kinv) / dist[:, None]
        drawn = ok & (np.abs(dist) >= 1e-9) & (x1y1 > x0y0).all(axis=1)  # not clipped away nor edge-on
        # each quad is warped into its screen box: the box's corner (x0, y0) becomes pixel (0, 0)
        H[:, :2] -= x0y0[:, :, None] * H[:, 2:3]
        boxes = np.hstack([x0y0, x1y1]).tolist()
        order = np.flatnonzero(drawn).tolist()
        _draw(image, inv_depth, order, boxes, H, level, seen, quads.shade[todo].tolist(), pts4, clipped, abe)
        if not with_depth:
            return image
        with np.errstate(divide="ignore"):
            depth = np.where(inv_depth > 0, 1.0 / inv_depth, np.inf).astype(np.float32)
        return image, depth

    def render_pair(
        self,
        T_world_camera,
        rng: np.random.Generator | None = None,
        with_depth: bool = False,
        time: float = 0.0,
    ):
        """Left and right images (and left depth) of the rig whose left camera is at ``T_world_camera``,
        with the movers where they are at ``time`` (seconds)."""
        T_left = np.asarray(T_world_camera, dtype=float)
        T_right = T_left.copy()
        T_right[:3, 3] = T_left[:3, 3] + T_left[:3, 0] * self.camera.baseline
        left = self.render(T_left, with_depth, time)
        left, depth = left if with_depth else (left, None)
        right = self.render(T_right, time=time)
        left, right = self.effects.apply(left, rng), self.effects.apply(right, rng)
        return (left, right, depth) if with_depth else (left, right)
