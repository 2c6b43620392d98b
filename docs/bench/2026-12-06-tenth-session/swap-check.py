import numpy as np
rng=np.random.default_rng(1)
f=np.float32
def test(org,dir,v0,v1,v2,tmax,swap):
    ad=np.abs(dir)
    kz=np.where(ad[:,0]>ad[:,1], np.where(ad[:,0]>ad[:,2],0,2), np.where(ad[:,1]>ad[:,2],1,2))
    kx=np.where(kz==2,0,kz+1); ky=np.where(kx==2,0,kx+1)
    idx=np.arange(len(dir))
    dz=dir[idx,kz]
    if swap:
        s=dz<0; kx2=np.where(s,ky,kx); ky2=np.where(s,kx,ky); kx,ky=kx2,ky2
    sx=(dir[idx,kx]/dz).astype(f); sy=(dir[idx,ky]/dz).astype(f); sz=(f(1)/dz).astype(f)
    a=(v0-org).astype(f); b=(v1-org).astype(f); c=(v2-org).astype(f)
    az,bz,cz=a[idx,kz],b[idx,kz],c[idx,kz]
    ax=a[idx,kx]-sx*az; ay=a[idx,ky]-sy*az
    bx=b[idx,kx]-sx*bz; by=b[idx,ky]-sy*bz
    cx=c[idx,kx]-sx*cz; cy=c[idx,ky]-sy*cz
    u=cx*by-cy*bx; v=ax*cy-ay*cx; w=bx*ay-by*ax
    rej=((u<0)|(v<0)|(w<0))&((u>0)|(v>0)|(w>0))
    det=u+v+w
    t=u*(sz*az)+v*(sz*bz)+w*(sz*cz)
    inside=np.where(det>0,(t>0)&(t<tmax*det),(t<0)&(t>tmax*det))
    hit=(~rej)&(det!=0)&inside
    with np.errstate(all='ignore'):
        r=np.where(hit,t/det,f(-1))
        bary=np.stack([u/det,v/det,w/det],1)
    return r.astype(f),np.where(hit[:,None],bary,0)
N=2_000_000
tot=0
with np.errstate(all='ignore'):
  for kind in range(4):
    if kind==0:   # continuous random
        org=rng.normal(size=(N,3)).astype(f); dir=rng.normal(size=(N,3)).astype(f)
        v0,v1,v2=[(rng.normal(size=(N,3))*2).astype(f) for _ in range(3)]
    elif kind==1: # small integer grid: edge/vertex hits, zeros
        org=rng.integers(-3,4,size=(N,3)).astype(f); dir=rng.integers(-2,3,size=(N,3)).astype(f)
        v0,v1,v2=[rng.integers(-3,4,size=(N,3)).astype(f) for _ in range(3)]
    elif kind==2: # half-integers
        org=(rng.integers(-6,7,size=(N,3))/2).astype(f); dir=rng.integers(-3,4,size=(N,3)).astype(f)
        v0,v1,v2=[(rng.integers(-6,7,size=(N,3))/2).astype(f) for _ in range(3)]
    else:  # huge/tiny magnitudes
        org=(rng.normal(size=(N,3))*10.0**rng.integers(-30,30,size=(N,1))).astype(f)
        dir=(rng.normal(size=(N,3))*10.0**rng.integers(-30,30,size=(N,1))).astype(f)
        v0,v1,v2=[(rng.normal(size=(N,3))*10.0**rng.integers(-30,30,size=(N,1))).astype(f) for _ in range(3)]
    ok=np.any(dir!=0,axis=1); org,dir,v0,v1,v2=org[ok],dir[ok],v0[ok],v1[ok],v2[ok]
    for tmax in (f(np.inf),f(3.0),f(0.0)):
        r1,b1=test(org,dir,v0,v1,v2,tmax,True); r2,b2=test(org,dir,v0,v1,v2,tmax,False)
        same=(r1.view(np.uint32)==r2.view(np.uint32))
        sb=((b1.astype(f).view(np.uint32)==b2.astype(f).view(np.uint32))|(np.isnan(b1)&np.isnan(b2))).all(1)
        print(kind,tmax,'hits',int((r1>=0).sum()),'t differ',int((~same).sum()),'bary differ',int((~sb).sum()))
        d=~sb
        if d.any():
            x=b1[d]; y=b2[d]
            print('   only zero signs:', bool(np.all((x==y)|(np.isnan(x)&np.isnan(y)))))
