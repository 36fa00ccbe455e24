import os, random, re, sys

from common import Tally, remove

# mesh_fuzz.py <strata> <cases> <seed>: mutated copies of mesh_seeds.py's files, `strata stats` on each.
BIN=sys.argv[1]; N=int(sys.argv[2]); seed=int(sys.argv[3])
rng=random.Random(seed)
srcs=['m.obj','m.off','ma.ply','mb.ply','ma.stl','mb.stl']
toks=[b'nan',b'inf',b'-inf',b'1e308',b'-1',b'0',b'4294967295',b'2147483648',b'99999999999',b'-2147483648',b'1e-320',b'',b'x',b'3 0 0 0',b'\x00',b'\n',b'f 1 1 1',b'v',b'element vertex 1000000000',b'property list uint int vertex_indices',b'format binary_big_endian 1.0',b'65535']
def mutate(d):
  d=bytearray(d)
  k=rng.randrange(6)
  if k==0 and len(d)>1: return bytes(d[:rng.randrange(len(d))])
  if k==1:
    for _ in range(rng.randint(1,8)):
      if d: d[rng.randrange(len(d))]=rng.randrange(256)
    return bytes(d)
  if k==2:
    # replace a numeric token
    ms=list(re.finditer(rb'-?\d+(\.\d+)?(e-?\d+)?',bytes(d)))
    if ms:
      m=rng.choice(ms); return bytes(d[:m.start()])+rng.choice(toks)+bytes(d[m.end():])
    return bytes(d)
  if k==3:
    lines=bytes(d).split(b'\n')
    i=rng.randrange(len(lines)); j=rng.randrange(len(lines))
    op=rng.randrange(3)
    if op==0: lines.insert(j,lines[i])
    elif op==1: del lines[i]
    else: lines[i]=rng.choice(toks)
    return b'\n'.join(lines)
  if k==4 and len(d)>8:
    # binary field overwrite with extreme ints
    i=rng.randrange(len(d)-4); d[i:i+4]=rng.choice([b'\xff\xff\xff\xff',b'\x00\x00\x00\x80',b'\x00\x00\xc0\x7f',b'\x00\x00\x80\x7f',b'\xff\xff\xff\x7f']); return bytes(d)
  if k==5 and len(d)>2:
    i=rng.randrange(len(d)); j=rng.randrange(len(d)); return bytes(d[:i]+d[j:])
  return bytes(d)
tally = Tally()
for it in range(N):
  src=rng.choice(srcs); d=open(src,'rb').read()
  for _ in range(rng.randint(1,3)): d=mutate(d)
  fn='case_%d_%d%s'%(seed,it,os.path.splitext(src)[1])
  open(fn,'wb').write(d)
  if tally.run('stats', fn, [BIN,'stats',fn], slow=20): remove(fn)
tally.summary(N)
