# Usage: python3 scripts/reference_dm.py chair|ellipsoid|tanglecube GRID_STEP MESH.ply
# (numpy, scipy, scikit-image, trimesh). Slow (minutes) at fine grids: not a test.
# Independent d_M of a catalog surface (no mesher code): marching cubes of f on a grid,
# Newton projection, shrinking balls (Ma et al. 2012) with exact gradient normals on both
# sides, d_M(x) = distance to the nearest medial-ball centre. Then, for a mesh written by
# the mesher, r / d_M(c) at every facet (c: circumcentre projected on S, r: |c - v|).
import numpy as np, sys, time
from skimage.measure import marching_cubes
from scipy.spatial import cKDTree
import trimesh
which, h, meshfile = sys.argv[1], float(sys.argv[2]), sys.argv[3]
if which == 'chair':
    R = 6.0
    def f(p):
        x,y,z = p[...,0],p[...,1],p[...,2]
        return (x*x+y*y+z*z-0.95*25)**2-0.8*((z-5)**2-2*x*x)*((z+5)**2-2*y*y)
    def grad(p):
        x,y,z = p[:,0],p[:,1],p[:,2]
        s = x*x+y*y+z*z-0.95*25; A = (z-5)**2-2*x*x; B = (z+5)**2-2*y*y
        return np.stack([4*s*x + 3.2*x*B, 4*s*y + 3.2*y*A, 4*s*z - 0.8*(2*(z-5)*B + A*2*(z+5))],1)
elif which == 'ellipsoid':
    R = 1.2
    def f(p): return p[...,0]**2+(p[...,1]/0.6)**2+(p[...,2]/0.4)**2-1
    def grad(p): return np.stack([2*p[:,0],2*p[:,1]/0.36,2*p[:,2]/0.16],1)
elif which == 'tanglecube':
    R = 3.0
    def f(p): return (p**4-5*p**2).sum(-1)+11.8
    def grad(p): return 4*p**3-10*p
def project(p, n=8):
    for _ in range(n):
        g = grad(p); v = f(p)
        p = p - (v/np.maximum((g*g).sum(1),1e-300))[:,None]*g
    return p
t = time.time()
n = int(2*R/h)+1
ax = np.linspace(-R, R, n)
vol = np.empty((n,n,n), np.float32)
Y, Z = np.meshgrid(ax, ax, indexing='ij')
for i in range(n):
    vol[i] = f(np.stack([np.full_like(Y, ax[i]), Y, Z], -1))
verts, faces, _, _ = marching_cubes(vol, 0.0, spacing=(ax[1]-ax[0],)*3)
del vol
p = project(verts - R)
nrm = grad(p); nrm /= np.linalg.norm(nrm, axis=1)[:,None]
tree = cKDTree(p)
print(f'{which}: reference sample {len(p)} points (grid {h}), {time.time()-t:.1f} s', flush=True)
def shrink(sign):
    r = np.full(len(p), 2.0*R)
    active = np.arange(len(p))
    for it in range(60):
        if len(active) == 0: break
        c = p[active] + sign*r[active,None]*nrm[active]
        d, j = tree.query(c, workers=2)
        q = p[j]; pq = q - p[active]
        den = 2*sign*(pq*nrm[active]).sum(1)
        ok = (d < r[active]*(1-1e-9)) & (j != active) & (den > 1e-12)
        newr = np.where(ok, (pq*pq).sum(1)/np.where(ok, den, 1.0), r[active])
        newr = np.minimum(newr, r[active])
        changed = newr < r[active]*(1-1e-12)
        r[active] = newr
        active = active[changed]
    return p + sign*r[:,None]*nrm
M = np.concatenate([shrink(-1.0), shrink(1.0)])
M = M[np.linalg.norm(M, axis=1) < 3*R]
mt = cKDTree(M)
dref, _ = mt.query(p, workers=2)
print(f'{which}: d_M^inf (reference) {dref.min():.4f}, median {np.median(dref):.4f}; {time.time()-t:.1f} s', flush=True)
# Vertex counts this mesher needs: its measured density, about 0.66 / sigma^2 (torus,
# ellipsoid), integrated over the area with sigma = e d_M.
tri = p[faces]
area = 0.5*np.linalg.norm(np.cross(tri[:,1]-tri[:,0], tri[:,2]-tri[:,0]), axis=1)
dface = dref[faces].mean(1)
for e in (0.09, 0.081):
    print(f'{which}: area {area.sum():.2f}; forecast at sigma = {e} d_M: {(0.66*area/(e*dface)**2).sum():.0f} vertices', flush=True)
m = trimesh.load(meshfile, process=False)
V = m.vertices; F = m.faces
a, b, c = V[F[:,0]], V[F[:,1]], V[F[:,2]]
ab, ac = b-a, c-a; n_ = np.cross(ab, ac)
cc = a + (np.cross(n_, ab)*(ac*ac).sum(1)[:,None] + np.cross(ac, n_)*(ab*ab).sum(1)[:,None])/(2*(n_*n_).sum(1))[:,None]
# the surface Delaunay ball's centre: the dual line through cc along the facet normal meets S;
# one Newton step along the normal direction, repeated (close to cc for a fine mesh).
nn = n_/np.linalg.norm(n_,axis=1)[:,None]
x = cc.copy()
for _ in range(8):
    g = grad(x); v = f(x); gn = (g*nn).sum(1)
    x = x - (v/np.where(np.abs(gn)>1e-300, gn, 1e-300))[:,None]*nn
ok = np.abs(f(x)) < 1e-6*np.abs(grad(x)).sum(1).clip(1) 
r = np.linalg.norm(x - a, axis=1)
dm, _ = mt.query(x, workers=2)
ratio = r/dm
print(f'{which}: {len(V)} vertices, {len(F)} facets; ball centres found {ok.mean()*100:.2f}%; '
      f'r/d_M(c): max {ratio[ok].max():.4f}, 99.9% {np.percentile(ratio[ok],99.9):.4f}, median {np.median(ratio[ok]):.4f}; '
      f'facets above 0.09: {(ratio[ok]>0.09).sum()}', flush=True)
