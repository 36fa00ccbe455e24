import random, subprocess, sys, os, re, time, json, struct, zlib
# strata_fuzz.py <strata> <cases> <seed> <model.strata> [opt]: mutated models, rewritten with valid
# CRC-32s; `strata info` and `export` on each, or with opt the options only, `info` and `edit`.
BIN=sys.argv[1]; N=int(sys.argv[2]); seed=int(sys.argv[3]); src=sys.argv[4]; OPT=len(sys.argv)>5
rng=random.Random(seed)
d=open(src,'rb').read()
H=struct.unpack('<I',d[12:16])[0]
hdr=json.loads(d[20:20+H])
secs={s['name']:d[s['offset']:s['offset']+s['size']] for s in hdr['sections']}
order=[s['name'] for s in hdr['sections']]
def pack(model, secs, order):
  def hdrbytes(offs):
    h={"format":"strata","version":1,"sections":[{"name":n,"offset":offs[i],"size":len(secs[n]),"crc32":zlib.crc32(secs[n])} for i,n in enumerate(order)],"model":model}
    return json.dumps(h,separators=(',',':')).encode()
  offs=[0]*len(order)
  for _ in range(5):
    hb=hdrbytes(offs); pos=20+len(hb); new=[]
    for n in order:
      pos=(pos+7)//8*8; new.append(pos); pos+=len(secs[n])
    if new==offs: break
    offs=new
  hb=hdrbytes(offs)
  out=bytearray(b'\x89STRATA\n'+struct.pack('<III',1,len(hb),zlib.crc32(hb))+hb)
  for i,n in enumerate(order):
    out+=b'\0'*(offs[i]-len(out)); out+=secs[n]
  return bytes(out)
assert pack(hdr['model'],secs,order)==d, "repack differs"
vals=[None,True,False,0,-1,1,2,3,0.5,-0.0,1e308,-1e308,2**31,2**32,2**53,2**63,-2**31,"",'x',[],{},[0],"band0.points",64,1e-300]
def paths(x,p=()):
  yield p
  if isinstance(x,dict):
    for k,v in x.items(): yield from paths(v,p+(k,))
  elif isinstance(x,list):
    for i,v in enumerate(x[:20]): yield from paths(v,p+(i,))
def setp(x,p,v):
  for k in p[:-1]: x=x[k]
  if v is KeyError:
    del x[p[-1]]
  else: x[p[-1]]=v
bad=0; hist={}
for it in range(N):
  model=json.loads(json.dumps(hdr['model'])); s2=dict(secs); o2=list(order)
  for _ in range(rng.randint(1,3)):
    k=0 if OPT else rng.randrange(5)
    if k<=1:
      ps=[p for p in paths(model) if p and (not OPT or (p[0]=='options' and len(p)>2))]
      p=rng.choice(ps)
      if k==0:
        cur=model
        for kk in p: cur=cur[kk]
        if OPT and isinstance(cur,(int,float)) and not isinstance(cur,bool) and rng.random()<0.8:
          f=rng.choice([0,0.001,0.1,10,1000,-1,2])
          nv=cur*f
          if isinstance(cur,int): nv=int(nv)
          setp(model,p,nv)
        elif OPT and isinstance(cur,bool): setp(model,p,not cur)
        else: setp(model,p,rng.choice(vals))
      else:
        try: setp(model,p,KeyError)
        except Exception: pass
    elif k==2:
      n=rng.choice(o2); b=bytearray(s2[n])
      if b:
        i=rng.randrange(len(b)); 
        if rng.random()<0.5: b[i:i+8]=rng.choice([struct.pack('<d',float('nan')),struct.pack('<d',1e308),struct.pack('<i',-1)*2,struct.pack('<i',2**31-1)*2,struct.pack('<d',0.0)])
        else: b[i]=rng.randrange(256)
      s2[n]=bytes(b[:len(s2[n])])
    elif k==3:
      n=rng.choice(o2); b=s2[n]; s2[n]=b[:rng.randrange(len(b)+1)//4*4] if rng.random()<0.5 else b+b[:rng.randrange(64)]
    else:
      n=rng.choice(o2)
      if rng.random()<0.5: o2.remove(n); del s2[n]
      else: o2.append(n+'x'); s2[n+'x']=s2[n]
  fn='s_%d_%d.strata'%(seed,it); open(fn,'wb').write(pack(model,s2,o2))
  for cmd in ((['info',fn],['edit',fn,'--band','0','--edit','cedit.json','-o','x_%d.strata'%seed,'-q']) if OPT else (['info',fn],['export',fn,'-o','x_%d.obj'%seed])):
    t=time.time()
    try:
      p=subprocess.run([BIN]+cmd,capture_output=True,timeout=300,env=dict(os.environ,ASAN_OPTIONS='detect_leaks=1:exitcode=86',UBSAN_OPTIONS='print_stacktrace=1:exitcode=87'))
      rc=p.returncode; err=p.stderr
    except subprocess.TimeoutExpired:
      rc='timeout'; err=b''
    dt=time.time()-t; hist[(cmd[0],rc)]=hist.get((cmd[0],rc),0)+1
    if rc not in (0,1,2) or dt>120:
      bad+=1; print('BAD',fn,cmd[0],rc,'%.1fs'%dt,err[-800:].decode(errors='replace').replace('\n',' | ')); sys.stdout.flush(); break
  else:
    os.remove(fn)
  for xf in ('x_%d.obj'%seed,'x_%d.strata'%seed):
    if os.path.exists(xf): os.remove(xf)
print('done',N,'bad',bad,hist)
