#!/usr/bin/env python3
"""Parts that need support, written as binary STL into the folder given (standard library only):
t-bracket (a 10 x 10 x 20 mm stem, a 40 x 10 x 5 mm bar: 15 mm overhangs), ledge-90 (a 20 mm
90-degree ledge), bridge-20 (two pillars, a 20 mm gap), sphere-on-stem (radius 10 mm on a
2.5 mm stem). Used by compare.sh and BENCHMARKS.md section 20. `parts.py DIR sphere-1m` writes
the 998 000-triangle sphere (radius 50 mm) of that section's speed figure instead."""
import math, os, struct, sys
def write_stl(path, tris):
    with open(path,'wb') as f:
        f.write(b'weft support part'.ljust(80,b' '))
        f.write(struct.pack('<I',len(tris)))
        for a,b,c in tris:
            ux,uy,uz=[b[i]-a[i] for i in range(3)]; vx,vy,vz=[c[i]-a[i] for i in range(3)]
            n=(uy*vz-uz*vy, uz*vx-ux*vz, ux*vy-uy*vx); l=math.sqrt(sum(x*x for x in n)) or 1
            f.write(struct.pack('<12fH',*(x/l for x in n),*a,*b,*c,0))
def tri_fan_polygon(poly):
    # ear clipping for simple polygon (CCW) in 2D
    pts=list(range(len(poly))); out=[]
    def area(a,b,c): return (poly[b][0]-poly[a][0])*(poly[c][1]-poly[a][1])-(poly[b][1]-poly[a][1])*(poly[c][0]-poly[a][0])
    def inside(p,a,b,c):
        d1=area(a,b,p);d2=area(b,c,p);d3=area(c,a,p)
        return d1>0 and d2>0 and d3>0
    guard=0
    while len(pts)>3 and guard<10000:
        guard+=1
        for i in range(len(pts)):
            a,b,c=pts[i-1],pts[i],pts[(i+1)%len(pts)]
            if area(a,b,c)<=1e-12: continue
            if any(inside(p,a,b,c) for p in pts if p not in (a,b,c)): continue
            out.append((a,b,c)); pts.pop(i); break
    out.append(tuple(pts)); return out
def extrude_xz(profile, y0, y1):
    # profile CCW in (x,z); extruded along y. returns triangles, outward normals
    s=sum(profile[i-1][0]*profile[i][1]-profile[i][0]*profile[i-1][1] for i in range(len(profile)))
    if s<0: profile=profile[::-1]
    tris=[]
    caps=tri_fan_polygon(profile)
    P=lambda i,y:(profile[i][0],y,profile[i][1])
    for a,b,c in caps:
        # profile CCW in (x,z) seen from -y ... choose orientation by test below
        tris.append((P(a,y0),P(c,y0),P(b,y0)))  # facing -y? check
        tris.append((P(a,y1),P(b,y1),P(c,y1)))
    n=len(profile)
    for i in range(n):
        j=(i+1)%n
        tris.append((P(i,y0),P(j,y0),P(j,y1))); tris.append((P(i,y0),P(j,y1),P(i,y1)))
    return fix_orientation(tris)
def fix_orientation(tris):
    vol=sum(a[0]*(b[1]*c[2]-b[2]*c[1])-a[1]*(b[0]*c[2]-b[2]*c[0])+a[2]*(b[0]*c[1]-b[1]*c[0]) for a,b,c in tris)
    return tris if vol>0 else [(a,c,b) for a,b,c in tris]
def revolve(profile, n=96):
    # profile: list of (r,z) from bottom axis point to top axis point (r=0 at ends)
    tris=[]
    ring=lambda r,z:[(r*math.cos(2*math.pi*k/n), r*math.sin(2*math.pi*k/n), z) for k in range(n)]
    rings=[ring(r,z) for r,z in profile]
    for a in range(len(profile)-1):
        A,B=rings[a],rings[a+1]
        for k in range(n):
            k1=(k+1)%n
            if profile[a][0]>0: tris.append((A[k],A[k1],B[k1]))
            if profile[a+1][0]>0: tris.append((A[k],B[k1],B[k]))
    return fix_orientation(tris)
def sphere_on_stem(R=10.0, stem_r=2.5, stem_h=4.0, n=96, m=48):
    zc=stem_h+math.sqrt(R*R-stem_r*stem_r)
    prof=[(0,0),(stem_r,0),(stem_r,stem_h)]
    # sphere from the angle where r=stem_r at bottom
    a0=math.asin(stem_r/R)
    for i in range(m+1):
        t=a0+(math.pi-a0)*i/m
        prof.append((R*math.sin(t), zc-R*math.cos(t)))
    prof[-1]=(0,zc+R)
    return revolve(prof,n)
def uv_sphere(path, R=50.0, S=1000, rings=500):
    """A closed UV sphere resting on the plate: 2 S (rings - 1) triangles (998 000 by default)."""
    def pt(i, j):
        th = math.pi * i / rings; ph = 2 * math.pi * j / S
        return (R * math.sin(th) * math.cos(ph), R * math.sin(th) * math.sin(ph), R - R * math.cos(th))
    n = 2 * S * (rings - 1)
    with open(path, 'wb') as f:
        f.write(b'weft uv sphere'.ljust(80, b' ')); f.write(struct.pack('<I', n))
        rec = struct.Struct('<12fH')
        prev = [pt(1, j) for j in range(S)]
        bottom, top = (0.0, 0.0, 0.0), (0.0, 0.0, 2 * R)
        for j in range(S):
            f.write(rec.pack(0, 0, 0, *bottom, *prev[(j + 1) % S], *prev[j], 0))
        for i in range(1, rings - 1):
            cur = [pt(i + 1, j) for j in range(S)]
            for j in range(S):
                a, b, c, d = prev[j], prev[(j + 1) % S], cur[(j + 1) % S], cur[j]
                f.write(rec.pack(0, 0, 0, *a, *b, *c, 0)); f.write(rec.pack(0, 0, 0, *a, *c, *d, 0))
            prev = cur
        for j in range(S):
            f.write(rec.pack(0, 0, 0, *top, *prev[j], *prev[(j + 1) % S], 0))

def main(out):
    parts = {
        't-bracket': extrude_xz([(15,0),(25,0),(25,20),(40,20),(40,25),(0,25),(0,20),(15,20)],0,10),
        'ledge-90': extrude_xz([(0,0),(10,0),(10,15),(30,15),(30,18),(0,18)],0,20),
        'bridge-20': extrude_xz([(0,0),(10,0),(10,10),(30,10),(30,0),(40,0),(40,13),(0,13)],0,10),
        'sphere-on-stem': sphere_on_stem(),
    }
    os.makedirs(out, exist_ok=True)
    for k, t in parts.items():
        write_stl(os.path.join(out, k + '.stl'), t)

if __name__ == '__main__':
    if len(sys.argv) > 2 and sys.argv[2] == 'sphere-1m':
        os.makedirs(sys.argv[1], exist_ok=True)
        uv_sphere(os.path.join(sys.argv[1], 'sphere-1m.stl'))
    else:
        main(sys.argv[1] if len(sys.argv) > 1 else '.')
