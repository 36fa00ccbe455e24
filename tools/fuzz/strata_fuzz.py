import json, os, random, struct, sys, zlib

from common import Tally, remove

# strata_fuzz.py <strata> <cases> <seed> <model.strata> [opt]: mutated models, rewritten with valid
# CRC-32s; `strata info` and `export` on each, or with opt the options only, `info` and `edit`
# (camel_edit.json, a band-0 move of the camel's cage).
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
tally = Tally()
EDIT = os.path.join(os.path.dirname(os.path.abspath(__file__)), 'camel_edit.json')
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
  out = 'x_%d.strata' % seed if OPT else 'x_%d.obj' % seed
  second = ['edit',fn,'--band','0','--edit',EDIT,'-o',out,'-q'] if OPT else ['export',fn,'-o',out]
  if all(tally.run(c[0], fn, [BIN]+c, slow=120, output=out) for c in (['info',fn], second)): remove(fn)
  remove(out)
tally.summary(N)
