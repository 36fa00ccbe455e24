# mesh_seeds.py: a level-1 icosphere as OBJ, OFF, ASCII and binary PLY, ASCII and binary STL.
import math, struct

t=(1+5**0.5)/2
V=[(-1,t,0),(1,t,0),(-1,-t,0),(1,-t,0),(0,-1,t),(0,1,t),(0,-1,-t),(0,1,-t),(t,0,-1),(t,0,1),(-t,0,-1),(-t,0,1)]
F=[(0,11,5),(0,5,1),(0,1,7),(0,7,10),(0,10,11),(1,5,9),(5,11,4),(11,10,2),(10,7,6),(7,1,8),(3,9,4),(3,4,2),(3,2,6),(3,6,8),(3,8,9),(4,9,5),(2,4,11),(6,2,10),(8,6,7),(9,8,1)]
V=[tuple(c/math.sqrt(sum(x*x for x in v)) for c in v) for v in V]
open('m.obj','w').write(''.join('v %r %r %r\n'%v for v in V)+''.join('f %d %d %d\n'%(a+1,b+1,c+1) for a,b,c in F))
open('m.off','w').write('OFF\n%d %d 0\n'%(len(V),len(F))+''.join('%r %r %r\n'%v for v in V)+''.join('3 %d %d %d\n'%f for f in F))
open('ma.ply','w').write('ply\nformat ascii 1.0\nelement vertex %d\nproperty float x\nproperty float y\nproperty float z\nelement face %d\nproperty list uchar int vertex_indices\nend_header\n'%(len(V),len(F))+''.join('%r %r %r\n'%v for v in V)+''.join('3 %d %d %d\n'%f for f in F))
h=('ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\nproperty float y\nproperty float z\nelement face %d\nproperty list uchar int vertex_indices\nend_header\n'%(len(V),len(F))).encode()
b=h+b''.join(struct.pack('<3f',*v) for v in V)+b''.join(struct.pack('<B3i',3,*f) for f in F)
open('mb.ply','wb').write(b)
def n(f):
  a,b_,c=[V[i] for i in f]
  u=[b_[k]-a[k] for k in range(3)]; w=[c[k]-a[k] for k in range(3)]
  return (u[1]*w[2]-u[2]*w[1],u[2]*w[0]-u[0]*w[2],u[0]*w[1]-u[1]*w[0])
s='solid m\n'+''.join('facet normal %r %r %r\nouter loop\n'%n(f)+''.join('vertex %r %r %r\n'%V[i] for i in f)+'endloop\nendfacet\n' for f in F)+'endsolid m\n'
open('ma.stl','w').write(s)
bb=b'\0'*80+struct.pack('<I',len(F))+b''.join(struct.pack('<12fH',*n(f),*V[f[0]],*V[f[1]],*V[f[2]],0) for f in F)
open('mb.stl','wb').write(bb)
