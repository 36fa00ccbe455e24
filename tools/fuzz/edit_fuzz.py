import random, subprocess, sys, os, re, time, json
# edit_fuzz.py <strata> <cases> <seed>: mutated edit scripts, `strata deform case/detail.obj` with each.
BIN=sys.argv[1]; N=int(sys.argv[2]); seed=int(sys.argv[3])
rng=random.Random(seed)
base=[
 '{"region": {"halfspace": {"point": [0, 0, 2], "normal": [0, 0, 1]}}, "handle": {"halfspace": {"point": [0, 0, 3.5], "normal": [0, 0, 1]}}, "transform": {"rotate": {"axis": [0, 1, 0], "degrees": 90, "pivot": [1.2, 0, 2.5]}}}',
 '{"edits": [{"region": {"sphere": {"center": [0, 0, 2], "radius": 1.5}}, "handle": {"box": {"min": [-2, -2, 2.5], "max": [2, 2, 3]}}, "transform": {"translate": [0.3, 0, 0]}}, {"region": {"halfspace": {"point": [0, 0, 1], "normal": [0, 0, -1]}}, "handle": {"vertices": [0, 1, 2, 3]}, "transform": {"scale": [1.2, 1.2, 1]}}]}',
]
toks=['NaN','1e308','-1e308','0','-1','1e-300','4294967295','2147483648','-2147483649','1e400','null','true','"x"','[]','{}','[0,0,0]','[1e308,1e308,1e308]','0.5','360000','-0.0']
bad=0; hist={}
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
  t=time.time()
  try:
    p=subprocess.run([BIN,'deform','case/detail.obj','--edit',fn,'-o',out,'-q'],capture_output=True,timeout=120,env=dict(os.environ,ASAN_OPTIONS='detect_leaks=1:exitcode=86',UBSAN_OPTIONS='print_stacktrace=1:exitcode=87'))
    rc=p.returncode; err=p.stderr
  except subprocess.TimeoutExpired:
    rc='timeout'; err=b''
  dt=time.time()-t; hist[rc]=hist.get(rc,0)+1
  tmpleft=[f for f in os.listdir('.') if '.tmp' in f]
  if rc not in (0,1,2) or dt>60 or tmpleft:
    bad+=1; print('BAD',fn,rc,'%.1fs'%dt,tmpleft,err[-500:].decode(errors='replace').replace('\n',' | ')); sys.stdout.flush()
  else:
    os.remove(fn)
  if os.path.exists(out): os.remove(out)
print("done",N,"bad",bad,hist)
