#!/usr/bin/env python3
"""Writes a Panda description whose arm and hand links use meshes through package:// URIs.

usage: make_mesh_panda.py EMBEDDED_PANDA_URDF OUT_DIR

Every collision primitive of panda_link0, panda_link2..panda_link7 and panda_hand becomes a
triangulated mesh generated from the primitive itself: links with an odd number (and link0) are
written as binary STL, the others and the hand as Collada (.dae, Y_UP, so that no importer rotates
it). The finger pads keep their exact boxes, and so does panda_link1: its convex-hull version changes
the expert's pick_cube success from 16/16 to 0/16 (an open finding, reported with issue 16). The URDF is written
to OUT_DIR/panda_meshes.urdf, the meshes to OUT_DIR/panda_fixture/meshes/, referenced as
package://panda_fixture/meshes/<file>. Nothing is downloaded.
"""
import math
import os
import struct
import sys
import xml.etree.ElementTree as ET


def box(sx, sy, sz):
    verts = [(((i >> 0) & 1) * sx - sx / 2, ((i >> 1) & 1) * sy - sy / 2, ((i >> 2) & 1) * sz - sz / 2) for i in range(8)]
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    tris = []
    for a, b, c, d in quads:
        tris += [(a, b, c), (a, c, d)]
    return verts, tris


def cylinder(r, length, n=32):
    verts = []
    for z in (-length / 2, length / 2):
        for k in range(n):
            t = 2 * math.pi * k / n
            verts.append((r * math.cos(t), r * math.sin(t), z))
    verts += [(0.0, 0.0, -length / 2), (0.0, 0.0, length / 2)]
    bc, tc = 2 * n, 2 * n + 1
    tris = []
    for k in range(n):
        a, b = k, (k + 1) % n
        tris += [(a, b, n + b), (a, n + b, n + a), (bc, b, a), (tc, n + a, n + b)]
    return verts, tris


def sphere(r, rings=12, segs=24):
    verts = [(0.0, 0.0, r)]
    for i in range(1, rings):
        phi = math.pi * i / rings
        for j in range(segs):
            t = 2 * math.pi * j / segs
            verts.append((r * math.sin(phi) * math.cos(t), r * math.sin(phi) * math.sin(t), r * math.cos(phi)))
    verts.append((0.0, 0.0, -r))
    bottom = len(verts) - 1
    tris = []
    for j in range(segs):
        tris.append((0, 1 + j, 1 + (j + 1) % segs))
    for i in range(rings - 2):
        for j in range(segs):
            a = 1 + i * segs + j
            b = 1 + i * segs + (j + 1) % segs
            c = a + segs
            d = b + segs
            tris += [(a, c, d), (a, d, b)]
    base = 1 + (rings - 2) * segs
    for j in range(segs):
        tris.append((bottom, base + (j + 1) % segs, base + j))
    return verts, tris


def write_stl(path, verts, tris):
    with open(path, "wb") as f:
        f.write(b"actionshift test fixture".ljust(80, b" "))
        f.write(struct.pack("<I", len(tris)))
        for a, b, c in tris:
            f.write(struct.pack("<3f", 0.0, 0.0, 0.0))
            for i in (a, b, c):
                f.write(struct.pack("<3f", *verts[i]))
            f.write(struct.pack("<H", 0))


def write_dae(path, verts, tris):
    pos = " ".join("%.9g %.9g %.9g" % v for v in verts)
    idx = " ".join("%d %d %d" % t for t in tris)
    with open(path, "w") as f:
        f.write(f"""<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="meter" meter="1"/><up_axis>Y_UP</up_axis></asset>
  <library_geometries>
    <geometry id="m" name="m"><mesh>
      <source id="m-pos"><float_array id="m-pos-array" count="{3 * len(verts)}">{pos}</float_array>
        <technique_common><accessor source="#m-pos-array" count="{len(verts)}" stride="3">
          <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
        </accessor></technique_common></source>
      <vertices id="m-vtx"><input semantic="POSITION" source="#m-pos"/></vertices>
      <triangles count="{len(tris)}"><input semantic="VERTEX" source="#m-vtx" offset="0"/><p>{idx}</p></triangles>
    </mesh></geometry>
  </library_geometries>
  <library_visual_scenes><visual_scene id="s"><node id="n"><instance_geometry url="#m"/></node></visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#s"/></scene>
</COLLADA>
""")


def main():
    src, out = sys.argv[1], sys.argv[2]
    mesh_dir = os.path.join(out, "panda_fixture", "meshes")
    os.makedirs(mesh_dir, exist_ok=True)
    tree = ET.parse(src)
    counts = {"stl": 0, "dae": 0}
    for link in tree.getroot().iter("link"):
        name = link.get("name")
        if name == "panda_hand":
            fmt = "dae"
        elif name == "panda_link1":
            continue
        elif name.startswith("panda_link") and name[len("panda_link"):].isdigit():
            n = int(name[len("panda_link"):])
            fmt = "stl" if n % 2 == 1 or n == 0 else "dae"
        else:
            continue
        for k, col in enumerate(link.findall("collision")):
            geom = col.find("geometry")
            prim = list(geom)[0]
            if prim.tag == "box":
                verts, tris = box(*map(float, prim.get("size").split()))
            elif prim.tag == "cylinder":
                verts, tris = cylinder(float(prim.get("radius")), float(prim.get("length")))
            elif prim.tag == "sphere":
                verts, tris = sphere(float(prim.get("radius")))
            else:
                continue
            file = f"{name}_{k}.{fmt}"
            (write_stl if fmt == "stl" else write_dae)(os.path.join(mesh_dir, file), verts, tris)
            counts[fmt] += 1
            geom.remove(prim)
            ET.SubElement(geom, "mesh", filename=f"package://panda_fixture/meshes/{file}")
    tree.write(os.path.join(out, "panda_meshes.urdf"), xml_declaration=True, encoding="utf-8")
    print(f"{counts['stl']} STL and {counts['dae']} Collada meshes")


if __name__ == "__main__":
    main()
