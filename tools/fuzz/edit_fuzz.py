import random, re, sys

from common import Tally, remove

# edit_fuzz.py <strata> <cases> <seed>: mutated edit scripts, `strata deform case/detail.obj` with each.
BIN=sys.argv[1]; N=int(sys.argv[2]); seed=int(sys.argv[3])
rng=random.Random(seed)
base=[
 '{"region": {"halfspace": {"point": [0, 0, 2], "normal": [0, 0, 1]}}, "handle": {"halfspace": {"point": [0, 0, 3.5], "normal": [0, 0, 1]}}, "transform": {"rotate": {"axis": [0, 1, 0], "degrees": 90, "pivot": [1.2, 0, 2.5]}}}',
 '{"edits": [{"region": {"sphere": {"center": [0, 0, 2], "radius": 1.5}}, "handle": {"box": {"min": [-2, -2, 2.5], "max": [2, 2, 3]}}, "transform": {"translate": [0.3, 0, 0]}}, {"region": {"halfspace": {"point": [0, 0, 1], "normal": [0, 0, -1]}}, "handle": {"vertices": [0, 1, 2, 3]}, "transform": {"scale": [1.2, 1.2, 1]}}]}',
]
toks=['NaN','1e308','-1e308','0','-1','1e-300','4294967295','2147483648','-2147483649','1e400','null','true','"x"','[]','{}','[0,0,0]','[1e308,1e308,1e308]','0.5','360000','-0.0']
tally = Tally()
for it in range(N):
  s=rng.choice(base)
  for _ in range(rng.randint(1,3)):
    ms=list(re.finditer(r'-?\d+(\.\d+)?(e-?\d+)?',s))
    k=rng.randrange(3)
    if k==0 and ms:
      m=rng.choice(ms); s=s[:m.start()]+rng.choice(toks)+s[m.end():]
    elif k==1:
      i=rng.randrange(len(s)); s=s[:i]+s[i+1:]
    else:
      keys=list(re.finditer(r'"[a-z_]+"',s))
      if keys:
        m=rng.choice(keys); s=s[:m.start()]+rng.choice(['"region"','"handle"','"transform"','"edits"','"vertices"','"sphere"','"box"','"halfspace"','"rotate"','"scale"','"translate"','"matrix"'])+s[m.end():]
  fn='e_%d_%d.json'%(seed,it); open(fn,'w').write(s)
  out='o_%d.obj'%seed
  if tally.run('deform', fn, [BIN,'deform','case/detail.obj','--edit',fn,'-o',out,'-q'], slow=60, output=out): remove(fn)
  remove(out)
tally.summary(N)
