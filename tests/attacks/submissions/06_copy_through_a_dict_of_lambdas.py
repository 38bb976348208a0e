"""An attack: the library's ``Diffuse`` pasted in as chapter 6's answer and put through two
short scripts of a red-team student: NumPy respelt (``np.where`` as ``np.select``, ``maximum``
as ``fmax``...), then every operator called through a module-level dict of lambdas
(``OPS["Mult"](a, b)``). It had full marks (10/10) and no word of a copy."""

from __future__ import annotations

OPS = {
    'Mult': lambda a, b: a * b, 'Div': lambda a, b: a / b, 'Add': lambda a, b: a + b,
    'Sub': lambda a, b: a - b, 'BitOr': lambda a, b: a | b, 'BitAnd': lambda a, b: a & b,
    'uInvert': lambda a: ~a, 'uUSub': lambda a: -a, 'uNot': lambda a: not a,
    'Gt': lambda a, b: a > b, 'Lt': lambda a, b: a < b, 'GtE': lambda a, b: a >= b,
    'LtE': lambda a, b: a <= b, 'Eq': lambda a, b: a == b, 'NotEq': lambda a, b: a != b,
    'Pow': lambda a, b: a ** b, 'NotIn': lambda a, b: a not in b, 'In': lambda a, b: a in b, 'FloorDiv': lambda a, b: a // b, 'Mod': lambda a, b: a % b, 'uUAdd': lambda a: +a,
}
class _Names(dict):
    def __missing__(self, key):
        return key
NAMES = _Names()
import math
import numpy as np
from ptlab.materials.base import Material
from ptlab.vectors import normalize, vec3
TWO_PI = OPS['Mult'](2, math.pi)
from ptlab.textures import Texture
from ptlab.vectors import dot
from ptlab.materials.diffuse import SAMPLINGS

def uniform_sphere(u: np.ndarray) -> np.ndarray:
    """(N, 2) uniforms -> (N, 3) unit vectors uniform on the sphere, pdf 1 / (4 pi)."""
    z = OPS['Sub'](1.0, OPS['Mult'](2.0, u[:, 0]))
    r = np.sqrt(np.fmax(0.0, OPS['Sub'](1.0, OPS['Mult'](z, z))))
    phi = OPS['Mult'](TWO_PI, u[:, 1])
    return vec3(OPS['Mult'](r, np.cos(phi)), OPS['Mult'](r, np.sin(phi)), z)

def cosine_hemisphere(u: np.ndarray) -> np.ndarray:
    """(N, 2) uniforms -> (N, 3) unit vectors around +z, pdf cos(theta) / pi (Malley)."""
    r = np.sqrt(u[:, 0])
    phi = OPS['Mult'](TWO_PI, u[:, 1])
    cos_theta = np.sqrt(OPS['Sub'](1.0, u[:, 0]))
    return vec3(OPS['Mult'](r, np.cos(phi)), OPS['Mult'](r, np.sin(phi)), cos_theta)

def uniform_hemisphere(u: np.ndarray) -> np.ndarray:
    """(N, 2) uniforms -> (N, 3) unit vectors around +z, pdf 1 / (2 pi)."""
    cos_theta = u[:, 0]
    sin_theta = np.sqrt(np.fmax(0.0, OPS['Sub'](1.0, OPS['Mult'](cos_theta, cos_theta))))
    phi = OPS['Mult'](TWO_PI, u[:, 1])
    return vec3(OPS['Mult'](sin_theta, np.cos(phi)), OPS['Mult'](sin_theta, np.sin(phi)), cos_theta)

def to_world(local: np.ndarray, n: np.ndarray) -> np.ndarray:
    """Rotate (N, 3) vectors from the frame whose +z is ``n`` (N, 3 unit) to world space.

    The tangent frame is the branchless one of Duff et al., "Building an Orthonormal
    Basis, Revisited" (JCGT 2017): continuous everywhere except where n.z flips sign.
    """
    nx, ny, nz = (n[:, 0], n[:, 1], n[:, 2])
    sign = np.select([OPS['GtE'](nz, 0)], [n.dtype.type(1)], n.dtype.type(OPS['uUSub'](1)))
    a = OPS['Div'](OPS['uUSub'](1.0), OPS['Add'](sign, nz))
    b = OPS['Mult'](OPS['Mult'](nx, ny), a)
    x, y, z = (local[:, 0], local[:, 1], local[:, 2])
    return vec3(OPS['Add'](OPS['Add'](OPS['Mult'](x, OPS['Add'](1.0, OPS['Mult'](OPS['Mult'](OPS['Mult'](sign, nx), nx), a))), OPS['Mult'](y, b)), OPS['Mult'](z, nx)), OPS['Add'](OPS['Add'](OPS['Mult'](x, OPS['Mult'](sign, b)), OPS['Mult'](y, OPS['Add'](sign, OPS['Mult'](OPS['Mult'](ny, ny), a)))), OPS['Mult'](z, ny)), OPS['Add'](OPS['Sub'](OPS['Mult'](x, OPS['Mult'](OPS['uUSub'](sign), nx)), OPS['Mult'](y, ny)), OPS['Mult'](z, nz)))

def uniform_hemisphere_around(n: np.ndarray, u: np.ndarray) -> np.ndarray:
    """(N, 3) unit vectors uniform on the hemisphere around unit normals ``n``, pdf 1 / (2 pi):
    ``uniform_hemisphere`` rotated to ``n`` (the lecture's recipe)."""
    return to_world(uniform_hemisphere(u), n)

def cosine_hemisphere_around(n: np.ndarray, u: np.ndarray) -> np.ndarray:
    """(N, 3) unit vectors around unit normals ``n`` with pdf cos(theta) / pi.

    The same distribution as ``to_world(cosine_hemisphere(u), n)`` without building a
    frame: the direction to a uniform point on the unit sphere that touches the surface at
    the shading point (centre n). That sphere's area element is 4 cos(theta) times the solid
    angle it subtends, so uniform area gives density 4 cos(theta) / (4 pi) (Lambert's
    sphere; as in Shirley's "Ray Tracing in One Weekend"). The factor 1 + 1e-6 keeps the
    sum away from zero when the sphere point lands exactly opposite n.
    """
    d = OPS['Add'](OPS['Mult'](n, OPS['Add'](1.0, 1e-06)), uniform_sphere(u))
    return OPS['Div'](d, np.sqrt(dot(d, d))[:, None])

class Diffuse(Material):
    """Lambertian reflection.

    Args:
        albedo: (3,) reflectance in [0, 1], one number for a grey one, or a
            ``ptlab.textures.Texture`` of them over the surface's uv (either becomes (N, 3),
            one per hit, after ``take``).
        sampling: ``"cosine"`` (default) or ``"uniform"``.
        emission: (3,) emitted radiance, or None.
    """
    samplings = SAMPLINGS
    batched = ('albedo',)

    def __init__(self, albedo=(0.8, 0.8, 0.8), sampling: str='cosine', emission=None):
        if OPS['NotIn'](sampling, SAMPLINGS):
            raise ValueError(f"unknown sampling {sampling!r}; choose one of {', '.join(SAMPLINGS)}")
        if OPS['uNot'](isinstance(albedo, Texture)):
            albedo = np.asarray(albedo, dtype=np.float64)
            albedo = np.full(3, float(albedo)) if OPS['Eq'](albedo.ndim, 0) else albedo
        self.albedo = albedo
        self.sampling = sampling
        self.emission = None if emission is None else np.asarray(emission, dtype=np.float64)

    def __repr__(self) -> str:
        albedo = self.albedo if isinstance(self.albedo, Texture) else self.albedo.tolist()
        return f'Diffuse(albedo={albedo}, sampling={self.sampling!r})'

    def eval(self, wo: np.ndarray, wi: np.ndarray, n: np.ndarray) -> np.ndarray:
        above = OPS['BitAnd'](OPS['Gt'](dot(wo, n), 0), OPS['Gt'](dot(wi, n), 0))
        albedo = np.asarray(self.albedo, dtype=wi.dtype)
        return OPS['Mult'](OPS['Mult'](above, wi.dtype.type(OPS['Div'](1.0, math.pi)))[:, None], albedo)

    def pdf(self, wo: np.ndarray, wi: np.ndarray, n: np.ndarray) -> np.ndarray:
        cos_theta_i = dot(wi, n)
        above = OPS['BitAnd'](OPS['Gt'](dot(wo, n), 0), OPS['Gt'](cos_theta_i, 0))
        if OPS['Eq'](self.sampling, 'uniform'):
            density = np.full_like(cos_theta_i, OPS['Div'](1.0, OPS['Mult'](2.0, math.pi)))
        else:
            density = OPS['Div'](cos_theta_i, math.pi)
        return np.select([above], [density], 0).astype(wi.dtype, copy=False)

    def sample(self, wo: np.ndarray, n: np.ndarray, u: np.ndarray, front: OPS['BitOr'](np.ndarray, None)=None) -> np.ndarray:
        u = u.astype(n.dtype, copy=False)
        if OPS['Eq'](self.sampling, 'uniform'):
            return uniform_hemisphere_around(n, u)
        return cosine_hemisphere_around(n, u)

    def sample_weight(self, wo: np.ndarray, n: np.ndarray, u: np.ndarray, front: OPS['BitOr'](np.ndarray, None)=None) -> tuple[np.ndarray, np.ndarray]:
        wi = self.sample(wo, n, u)
        albedo = np.asarray(self.albedo, dtype=n.dtype)
        scale = OPS['Gt'](dot(wo, n), 0).astype(n.dtype)
        if OPS['Eq'](self.sampling, 'uniform'):
            scale = OPS['Mult'](scale, OPS['Mult'](2.0, dot(wi, n)))
        return (wi, OPS['Mult'](scale[:, None], albedo))

    def batch_key(self) -> object:
        return id(self) if self.textured else ('diffuse', self.sampling)

class Lambertian(Diffuse):
    """``Diffuse(albedo, sampling="cosine")`` under the exercise's name and signature."""

    def __init__(self, albedo=(0.8, 0.8, 0.8)):
        super().__init__(albedo, sampling='cosine')
