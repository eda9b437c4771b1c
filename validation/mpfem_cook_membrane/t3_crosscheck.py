# independent cross-check of the reference point (README.md): plain linear triangles (T3) on a Gmsh .msh of the
# Cook membrane, plane stress E = 1, nu = 1/3; prints nodes, u_y(48, 60), u_y(48, 52), u_x(48, 60). Not a reference.
# usage: /usr/bin/python3 t3_crosscheck.py cook_h1.msh
import numpy as np, scipy.sparse as sp, scipy.sparse.linalg as sla, sys
def read(path):
    L=open(path).read().split('\n'); i=L.index('$Nodes'); n=int(L[i+1]); X=np.array([[float(v) for v in L[i+2+k].split()[1:3]] for k in range(n)])
    tag={int(L[i+2+k].split()[0]):k for k in range(n)}
    j=L.index('$Elements'); m=int(L[j+1]); T=[]
    for k in range(m):
        f=L[j+2+k].split()
        if f[1]=='2': nt=int(f[2]); T.append([tag[int(v)] for v in f[3+nt:6+nt]])
    return X,np.array(T)
X,T=read(sys.argv[1]); E=1.0; nu=1/3
C=E/(1-nu**2)*np.array([[1,nu,0],[nu,1,0],[0,0,(1-nu)/2]])
n=len(X); rows=[];cols=[];vals=[]
for t in T:
    x=X[t]; A=0.5*((x[1,0]-x[0,0])*(x[2,1]-x[0,1])-(x[2,0]-x[0,0])*(x[1,1]-x[0,1]))
    b=np.array([x[1,1]-x[2,1],x[2,1]-x[0,1],x[0,1]-x[1,1]])/(2*A); c=np.array([x[2,0]-x[1,0],x[0,0]-x[2,0],x[1,0]-x[0,0]])/(2*A)
    B=np.zeros((3,6)); B[0,0::2]=b; B[1,1::2]=c; B[2,0::2]=c; B[2,1::2]=b
    K=abs(A)*B.T@C@B; d=np.array([[2*a,2*a+1] for a in t]).ravel()
    rows+=list(np.repeat(d,6)); cols+=list(np.tile(d,6)); vals+=list(K.ravel())
K=sp.csr_matrix((vals,(rows,cols)),shape=(2*n,2*n)); f=np.zeros(2*n)
r=np.where(X[:,0]>48-1e-9)[0]; r=r[np.argsort(X[r,1])]
for a,b in zip(r[:-1],r[1:]): L=X[b,1]-X[a,1]; f[2*a+1]+=L/32; f[2*b+1]+=L/32
fixed=np.where(X[:,0]<1e-9)[0]; fd=np.concatenate([2*fixed,2*fixed+1]); free=np.setdiff1d(np.arange(2*n),fd)
u=np.zeros(2*n); u[free]=sla.spsolve(K[free][:,free].tocsc(),f[free])
tip=np.where((abs(X[:,0]-48)<1e-9)&(abs(X[:,1]-60)<1e-9))[0][0]
print(n, u[2*tip+1])
m=np.where((abs(X[:,0]-48)<1e-9)&(abs(X[:,1]-52)<1e-9))[0]
print('mid', u[2*m[0]+1] if len(m) else None, 'ux tip', u[2*tip])
