"""A heterogeneous medium on a 3D grid (Mitsuba's `heterogeneous` medium with `gridvolume`s): voxel
lookups, free-flight sampling by delta tracking and transmittance by ratio tracking, in f32 with
bounded loops (valid on CUDA and Vulkan). Numpy references of the lookups close the module.

Placement. A grid fills the unit cube [0, 1]^3 of its `to_world`; a world point p is looked up at
q = to_local p. Voxel values sit at the cell centres: trilinear lookups interpolate between the
eight around q * res - 1/2, clamped at the faces (Mitsuba's default filter and wrap mode);
nearest lookups take voxel floor(q * res). The medium exists only inside its density grid's cube
(Mitsuba clips rays to the extinction volume's bounding box), whatever shape holds it.

Tracking. The majorant mu = scale * max(density) bounds sigma_t = scale * density everywhere
(neither lookup exceeds its largest voxel), so the medium plus "null" particles of density
sigma_n = mu - sigma_t >= 0 is homogeneous with extinction mu: tentative collisions are
exponential steps of rate mu.

* Transmittance (ratio tracking, Novak et al. 2014): the product of sigma_n / mu over the
  tentative collisions before the end of the segment; its expectation is exp(-integral sigma_t).
* Free flight (spectral tracking, Kutz et al. 2017, without absorption events): at each tentative
  collision the path scatters with probability P = <h, sigma_s> / (<h, sigma_s> + <h, sigma_n>),
  h the path's throughput so far (the channels it still carries), weight sigma_s / (mu P); else it
  goes on, weight sigma_n / (mu (1 - P)). Absorption is in the weights instead of an event, so an
  absorbing medium (albedo 0) is ratio tracking for the camera path: its transmittance, never a
  terminated path. In a grey medium of albedo 1 every weight is 1 (plain delta tracking).
  E[weight; no collision before t_max] = T(t_max) and E[weight; scattering in dt] =
  sigma_s(t) T(t) dt per channel: the homogeneous medium's contract (homogeneous.py).

Random numbers. The number of steps is unbounded, so a segment draws from its own hashed stream
(`tracking_key`: the camera sample, the decision's dimension and a salt), step k taking numbers
2k and 2k + 1. Loops stop after MAX_TRACKING_STEPS collisions, an optical thickness of the
majorant far beyond anything that still transmits.
"""
import numpy as np
import taichi as ti

from renderer.media.homogeneous import T_MAX_CLAMP, MediumSample
from renderer.sampling.rng import pcg_hash, uniform

vec3, vec4 = ti.math.vec3, ti.math.vec4
MAX_TRACKING_STEPS = 1 << 16
NO_GRID = -1  # GridMediumRecord.density of a medium that is not a grid

# One grid on the device: rows of the world -> unit-cube affine map, resolution (x, y, z), where
# its voxels start in the voxel field (floats), 1 or 3 channels, nearest (1) or trilinear (0).
GridVolume = ti.types.struct(row0=vec4, row1=vec4, row2=vec4, res=ti.math.ivec3, offset=ti.i32,
                             channels=ti.i32, nearest=ti.i32)
# One medium: its density and albedo grids (indices of GridVolume rows; density NO_GRID for a
# medium that is not a grid), the density's scale and the majorant scale * max(density).
GridMediumRecord = ti.types.struct(density=ti.i32, albedo=ti.i32, scale=ti.f32, majorant=ti.f32)


@ti.func
def tracking_key(state, dim, salt):
    """The key of a tracking loop's stream: the camera sample (SampleState: the pixel's key and the
    sample's index, both samplers set them), the decision's dimension, and a salt that tells apart
    segments drawn at the same dimension (a shadow ray's pieces between null surfaces)."""
    k = pcg_hash(state.key ^ pcg_hash(state.index + ti.u32(0x2545F491)))
    return pcg_hash(k ^ pcg_hash(ti.cast(dim, ti.u32) * ti.u32(0x9E3779B1) ^ ti.cast(salt, ti.u32)))


@ti.func
def point_salt(p):
    """A salt from a point's bits: segments that start at different points draw different streams."""
    h = pcg_hash(ti.bit_cast(p.x, ti.u32))
    h = pcg_hash(h ^ ti.bit_cast(p.y, ti.u32))
    return pcg_hash(h ^ ti.bit_cast(p.z, ti.u32))


@ti.func
def _to_local(v, p, w):
    """The affine map of grid v applied to (p, w): w = 1 for points, 0 for directions."""
    h = vec4(p, w)
    return vec3(v.row0.dot(h), v.row1.dot(h), v.row2.dot(h))


@ti.func
def clip_to_grid(v, o, d, t_max):
    """(t0, t1): the part of the ray o + t d, 0 <= t <= t_max, inside grid v's cube (t0 >= t1: none).
    Affine maps keep the ray's parameter, so the slabs are tested in the grid's own space."""
    ol = _to_local(v, o, 1.0)
    dl = _to_local(v, d, 0.0)
    t0 = 0.0
    t1 = ti.min(t_max, T_MAX_CLAMP)
    for a in ti.static(range(3)):
        if dl[a] != 0.0:
            inv = 1.0 / dl[a]
            ta = -ol[a] * inv
            tb = (1.0 - ol[a]) * inv
            t0 = ti.max(t0, ti.min(ta, tb))
            t1 = ti.min(t1, ti.max(ta, tb))
        elif ol[a] < 0.0 or ol[a] > 1.0:
            t1 = -1.0  # parallel to these faces and outside them
    return t0, t1


@ti.func
def _voxel(voxels: ti.template(), v, i):
    base = v.offset + ((i.z * v.res.y + i.y) * v.res.x + i.x) * v.channels
    out = vec3(voxels[base])
    if v.channels == 3:
        out = vec3(voxels[base], voxels[base + 1], voxels[base + 2])
    return out


@ti.func
def lookup(volumes: ti.template(), voxels: ti.template(), index, p):
    """Grid `index` at world point p (RGB; a one-channel grid in every channel)."""
    v = volumes[index]
    q = _to_local(v, p, 1.0)
    top = v.res - 1
    out = vec3(0.0)
    if v.nearest == 1:
        out = _voxel(voxels, v, ti.math.clamp(ti.cast(ti.floor(q * v.res), ti.i32), 0, top))
    else:
        x = ti.math.clamp(q * v.res - 0.5, 0.0, ti.cast(top, ti.f32))
        i0 = ti.math.min(ti.cast(ti.floor(x), ti.i32), top)
        i1 = ti.math.min(i0 + 1, top)
        f = x - ti.cast(i0, ti.f32)
        for corner in ti.static(range(8)):
            dx, dy, dz = ti.static(corner & 1, (corner >> 1) & 1, corner >> 2)
            i = ti.math.ivec3(i1.x if dx else i0.x, i1.y if dy else i0.y, i1.z if dz else i0.z)
            w = (f.x if dx else 1.0 - f.x) * (f.y if dy else 1.0 - f.y) * (f.z if dz else 1.0 - f.z)
            out += w * _voxel(voxels, v, i)
    return out


@ti.func
def ratio_tracking(media: ti.template(), volumes: ti.template(), voxels: ti.template(), medium, o, d, t_end, key):
    """Transmittance (RGB) of grid medium `medium` along o + t d, 0 <= t <= t_end (module doc)."""
    rec = media[medium]
    tr = vec3(1.0)
    t0, t1 = clip_to_grid(volumes[rec.density], o, d, t_end)
    mu = rec.majorant
    if t0 < t1 and mu > 0.0:
        t = t0
        for step in range(MAX_TRACKING_STEPS):
            t += -ti.log(1.0 - uniform(key, step)) / mu  # 1 - u in (0, 1]: the log is finite
            if t >= t1:
                break
            sigma_t = rec.scale * lookup(volumes, voxels, rec.density, o + t * d)
            tr *= ti.max(1.0 - sigma_t / mu, 0.0)
            if tr.max() <= 0.0:
                break
    return tr


@ti.func
def delta_tracking(media: ti.template(), volumes: ti.template(), voxels: ti.template(), medium, o, d, t_max,
                   throughput, key):
    """A MediumSample of grid medium `medium` along o + t d up to t_max (the surface; may be
    infinite): where it scatters, if it does, and the weight (module doc)."""
    rec = media[medium]
    weight = vec3(1.0)
    t_hit = ti.min(t_max, T_MAX_CLAMP)
    t_out = t_hit
    scattered = 0
    t0, t1 = clip_to_grid(volumes[rec.density], o, d, t_hit)
    mu = rec.majorant
    if t0 < t1 and mu > 0.0:
        t = t0
        for step in range(MAX_TRACKING_STEPS):
            t += -ti.log(1.0 - uniform(key, 2 * step)) / mu
            if t >= t1:
                break
            p = o + t * d
            sigma_t = rec.scale * lookup(volumes, voxels, rec.density, p)
            sigma_s = sigma_t * lookup(volumes, voxels, rec.albedo, p)
            sigma_n = ti.max(mu - sigma_t, 0.0)
            h = throughput * weight
            scatter = (h * sigma_s).sum()
            null = (h * sigma_n).sum()
            if scatter + null <= 0.0:
                weight = vec3(0.0)  # all the light the path still carries is absorbed here
                break
            if uniform(key, 2 * step + 1) * (scatter + null) < scatter:
                weight *= sigma_s * ((scatter + null) / (mu * scatter))
                scattered = 1
                t_out = t
                break
            weight *= sigma_n * ((scatter + null) / (mu * null))
    return MediumSample(t=t_out, scattered=scattered, weight=weight)


# --- numpy references (float64) -----------------------------------------------------------------


def lookup_np(values, to_local, points, nearest=False):
    """Grid `values` (zres, yres, xres, channels) at world points (N, 3), `to_local` 4x4."""
    values = np.asarray(values, np.float64)
    res = np.array(values.shape[2::-1])  # (x, y, z)
    q = (np.c_[np.asarray(points, np.float64), np.ones(len(points))] @ np.asarray(to_local, np.float64).T)[:, :3]
    if nearest:
        i = np.clip(np.floor(q * res).astype(np.int64), 0, res - 1)
        return values[i[:, 2], i[:, 1], i[:, 0]]
    x = np.clip(q * res - 0.5, 0.0, res - 1)
    i0 = np.minimum(np.floor(x).astype(np.int64), res - 1)
    i1 = np.minimum(i0 + 1, res - 1)
    f = x - i0
    out = 0.0
    for corner in range(8):
        pick = [(corner >> a) & 1 for a in range(3)]
        i = np.where(pick, i1, i0)
        w = np.prod(np.where(pick, f, 1.0 - f), axis=1)
        out = out + w[:, None] * values[i[:, 2], i[:, 1], i[:, 0]]
    return out
