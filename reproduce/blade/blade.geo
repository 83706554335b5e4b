// A representative compressor rotor blade for LL11 Sec. 5.2 (the paper's industrial blade is not
// public). Meshed by gmsh into quadratic tetrahedra (C3D10) by reproduce/ll11_blade; SI units (m).
// Geometry, and why (reproduce/blade/README.md):
//  - span 100 mm, chord 60 mm at the root tapering to 45 mm at the tip: a front-stage
//    high-pressure-compressor rotor blade of a mid-size turbofan (aspect ratio ~2);
//  - NACA 4-digit thickness, 10 % of the chord at the root to 5 % at the tip, with a blunt
//    trailing edge 0.8 mm thick (a machined blade has no knife edge, and a sharp one would force
//    tiny elements); parabolic camber line, 8 % to 4 % camber;
//  - stagger from 25° at the root to 50° at the tip (25° of twist), sections stacked at
//    mid-chord on the radial line x = y = 0;
//  - ntip = 24 points embedded in the tip face on the camber line, 4 % to 96 % of the chord (leading to
//    trailing edge): they become mesh nodes, the node set TIP, the contact interface.
// The engine axis is parallel to x at z = -0.25 m (hub radius 250 mm at the root); the root face
// z = 0 is clamped by the model deck (blade.inp); the casing is at a uniform radial gap.
// Parameters: size, the largest element edge [m] (-setnumber size 0.0025: about 14 400 nodes);
// ntip, the number of contact points (24, as the paper; bench/ varies it).
SetFactory("OpenCASCADE");
span = 0.10;  c_root = 0.060; c_tip = 0.045;   // m
t_root = 0.10; t_tip = 0.05;                   // thickness / chord
h_root = 0.08; h_tip = 0.04;                   // camber / chord
stag_root = 25*Pi/180; stag_tip = 50*Pi/180;   // stagger from the engine axis x
te_half = 0.0004;                              // half the trailing-edge thickness [m]
nsec = 5; npts = 18;
If (!Exists(ntip)) ntip = 24; EndIf      // contact points on the tip camber line
If (!Exists(size)) size = 0.0025; EndIf

wires[] = {};
For k In {0:nsec-1}
  s = k/(nsec-1);
  c = c_root + (c_tip-c_root)*s; t = t_root + (t_tip-t_root)*s; h = h_root + (h_tip-h_root)*s;
  g = stag_root + (stag_tip-stag_root)*s; z = span*s;
  up[] = {}; lo[] = {};
  For i In {0:npts-1}
    x = 0.5*(1-Cos(Pi*i/(npts-1)));  // chord fraction, cosine spacing
    yt = 5*t*(0.2969*Sqrt(x)-0.1260*x-0.3516*x^2+0.2843*x^3-0.1036*x^4) + te_half/c*x;
    yc = 4*h*x*(1-x);
    xl = (x-0.5)*c; yu = (yc+yt)*c; yl = (yc-yt)*c;
    p = newp; Point(p) = {Cos(g)*xl - Sin(g)*yu, Sin(g)*xl + Cos(g)*yu, z}; up[] += p;
    If (i == 0)
      lo[] += p;
    Else
      p = newp; Point(p) = {Cos(g)*xl - Sin(g)*yl, Sin(g)*xl + Cos(g)*yl, z}; lo[] += p;
    EndIf
  EndFor
  // suction side trailing edge -> leading edge, pressure side leading -> trailing edge, then the
  // blunt trailing edge (three curves: each side surface is a well-parametrized patch)
  pts[] = {};
  For i In {npts-1:0:-1}
    pts[] += up[i];
  EndFor
  l1 = newl; Spline(l1) = pts[];
  l2 = newl; Spline(l2) = lo[];
  l3 = newl; Line(l3) = {lo[npts-1], up[npts-1]};
  w = newll; Curve Loop(w) = {l1, l2, l3};
  wires[] += w;
EndFor
ThruSections(1) = {wires[]};

eps = 1e-4;
tip() = Surface In BoundingBox{-1, -1, span-eps, 1, 1, span+eps};
tp[] = {};
c = c_tip; h = h_tip; g = stag_tip;
For i In {0:ntip-1}
  x = 0.04 + 0.92*i/(ntip-1);
  xl = (x-0.5)*c; yc = 4*h*x*(1-x)*c;
  p = newp; Point(p) = {Cos(g)*xl - Sin(g)*yc, Sin(g)*xl + Cos(g)*yc, span}; tp[] += p;
EndFor
Point{tp[]} In Surface{tip[0]};

Physical Volume("BLADE") = {1};
Physical Point("TIP") = {tp[]};
Mesh.CharacteristicLengthMax = size;
Mesh.ElementOrder = 2;
Mesh.SecondOrderLinear = 1;   // straight-sided quadratic tetrahedra: never inverted
Mesh.SaveGroupsOfNodes = 1;   // *NSET TIP (and BLADE) in the .inp
