import sys, numpy as np
def readpfm(p):
    f=open(p,'rb'); h=f.readline().strip(); w,hh=map(int,f.readline().split()); sc=float(f.readline())
    d=np.frombuffer(f.read(),dtype='<f4' if sc<0 else '>f4'); return d.reshape(hh,w,-1)
a=readpfm(sys.argv[1]); b=readpfm(sys.argv[2])
print("means", a.mean(axis=(0,1)), b.mean(axis=(0,1)), "rel diff of means", (b.mean()-a.mean())/a.mean())
# blockwise 8x8 means compare
def blk(x): H,W,C=x.shape; return x[:H//8*8,:W//8*8].reshape(H//8,8,W//8,8,C).mean(axis=(1,3))
A,B=blk(a),blk(b); print("block rel rms", np.sqrt(((A-B)**2).mean())/A.mean(), "max block rel", np.abs(A-B).max()/A.mean())
