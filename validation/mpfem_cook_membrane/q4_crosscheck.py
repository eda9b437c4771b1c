# independent check of the reference point (README.md): plain bilinear quadrilaterals (Q4, 2 x 2 Gauss) on
# the structured N x N mesh of the Cook membrane that the element literature uses, plane stress E = 1,
# nu = 1/3, uniform shear 1/16 on x = 48 (consistent nodal forces); prints u_y at the upper corner
# (48, 60), the midpoint of the loaded edge (48, 52) and the lower corner (48, 44). Not a reference.
# usage: /usr/bin/python3 q4_crosscheck.py [N ...]      (default 2 4 8 16 32 64)
import sys
import numpy as np, scipy.sparse as sp, scipy.sparse.linalg as sla

E, nu = 1.0, 1 / 3
C = E / (1 - nu**2) * np.array([[1, nu, 0], [nu, 1, 0], [0, 0, (1 - nu) / 2]])

def run(N):
    s = np.linspace(0, 1, N + 1)
    # bilinear map of the unit square: bottom edge (0,0)-(48,44), top edge (0,44)-(48,60)
    X = np.array([[48 * xi, 44 * xi + (44 - 28 * xi) * eta] for eta in s for xi in s])
    idx = lambda i, j: j * (N + 1) + i
    g = [-1 / np.sqrt(3), 1 / np.sqrt(3)]
    rows, cols, vals = [], [], []
    for j in range(N):
        for i in range(N):
            nd = [idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)]
            x = X[nd]; K = np.zeros((8, 8))
            for a in g:
                for b in g:
                    dN = 0.25 * np.array([[-(1 - b), 1 - b, 1 + b, -(1 + b)], [-(1 - a), -(1 + a), 1 + a, 1 - a]])
                    J = dN @ x; d = np.linalg.solve(J, dN)
                    B = np.zeros((3, 8)); B[0, 0::2] = d[0]; B[1, 1::2] = d[1]; B[2, 0::2] = d[1]; B[2, 1::2] = d[0]
                    K += B.T @ C @ B * np.linalg.det(J)
            dofs = np.array([[2 * q, 2 * q + 1] for q in nd]).ravel()
            rows += list(np.repeat(dofs, 8)); cols += list(np.tile(dofs, 8)); vals += list(K.ravel())
    n = len(X)
    K = sp.csr_matrix((vals, (rows, cols)), shape=(2 * n, 2 * n)); f = np.zeros(2 * n)
    for j in range(N):
        a, b = idx(N, j), idx(N, j + 1); L = X[b, 1] - X[a, 1]
        f[2 * a + 1] += L / 32; f[2 * b + 1] += L / 32
    fixed = np.array([idx(0, j) for j in range(N + 1)])
    free = np.setdiff1d(np.arange(2 * n), np.concatenate([2 * fixed, 2 * fixed + 1]))
    u = np.zeros(2 * n); u[free] = sla.spsolve(K[free][:, free].tocsc(), f[free])
    print(f"{N:4d} x {N:<4d} upper corner {u[2 * idx(N, N) + 1]:.4f}  midpoint {u[2 * idx(N, N // 2) + 1]:.4f}"
          f"  lower corner {u[2 * idx(N, 0) + 1]:.4f}")

for N in [int(a) for a in sys.argv[1:]] or [2, 4, 8, 16, 32, 64]:
    run(N)
