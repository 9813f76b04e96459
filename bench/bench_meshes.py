"""Time loading a world full of meshes: reading the files and covering them with boxes.

The world is a furnished room of MODELS models (default 120), each a mesh
visual of one of a dozen generated files (STL, OBJ and Collada tables,
chairs, spheres and tori of a dozen to 20,000 triangles; STL binary, as
CAD programs write it, OBJ and Collada as text), with no
collision of its own, so each mesh also collides. Printed: importing
trimesh and loading the compiled piece finder (once per process; the
simulator has numba going for its sensors anyway), the first load (every file read and covered),
and a load of the same world again (files and boxes kept while the files stay
as they are), each the median of --repeat fresh processes, in wall and CPU
seconds (wall time suffers when other processes share the cores). Nothing
here asserts on time.

    python bench/bench_meshes.py [--models 120] [--repeat 3]
"""
import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile

import numpy as np

SOURCE = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'catkin_ws', 'src',
                      'flatsim', 'src')
sys.path.insert(0, SOURCE)


def box(size, centre):
    corners = np.array([[x, y, z] for x in (-.5, .5) for y in (-.5, .5) for z in (-.5, .5)])
    faces = np.array([[0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3], [0, 4, 5], [0, 5, 1],
                      [2, 3, 7], [2, 7, 6], [0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5]])
    return corners * np.asarray(size) + np.asarray(centre), faces


def joined(parts):
    vertices, faces, count = [], [], 0
    for part_vertices, part_faces in parts:
        vertices.append(part_vertices)
        faces.append(part_faces + count)
        count += len(part_vertices)
    return np.vstack(vertices), np.vstack(faces)


def grid_faces(rings, sides, wrap_sides):
    """Two triangles per cell of a rings x sides grid of vertices, round in rings."""
    faces = []
    for i in range(rings):
        for j in range(sides if wrap_sides else sides - 1):
            a, b = i * sides + j, ((i + 1) % rings) * sides + j
            c, d = ((i + 1) % rings) * sides + (j + 1) % sides, i * sides + (j + 1) % sides
            faces += [[a, b, c], [a, c, d]]
    return np.array(faces)


def torus(rings, sides, major=0.3, minor=0.1, height=0.4):
    u, v = np.meshgrid(np.linspace(0, 2 * math.pi, rings, endpoint=False),
                       np.linspace(0, 2 * math.pi, sides, endpoint=False), indexing='ij')
    vertices = np.stack([(major + minor * np.cos(v)) * np.cos(u),
                         (major + minor * np.cos(v)) * np.sin(u), height + minor * np.sin(v)],
                        axis=-1).reshape(-1, 3)
    return vertices, grid_faces(rings, sides, True)


def sphere(rings, sides, radius=0.3, height=0.3):
    """A sphere without its two polar caps."""
    t, p = np.meshgrid(np.linspace(0, 2 * math.pi, rings, endpoint=False),
                       np.linspace(0.05, math.pi - 0.05, sides), indexing='ij')
    vertices = np.stack([radius * np.sin(p) * np.cos(t), radius * np.sin(p) * np.sin(t),
                         height + radius * np.cos(p)], axis=-1).reshape(-1, 3)
    return vertices, grid_faces(rings, sides, False)


def table(top=(1.2, 0.8, 0.04), height=0.75):
    parts = [box(top, (0, 0, height - top[2] / 2))]
    parts += [box((0.05, 0.05, height - top[2]), (x * 0.55, y * 0.35, (height - top[2]) / 2))
              for x in (-1, 1) for y in (-1, 1)]
    return joined(parts)


def chair():
    parts = [box((0.45, 0.45, 0.04), (0, 0, 0.45)), box((0.04, 0.45, 0.5), (-0.2, 0, 0.72))]
    parts += [box((0.04, 0.04, 0.43), (x * 0.2, y * 0.2, 0.215)) for x in (-1, 1) for y in (-1, 1)]
    return joined(parts)


def write(path, vertices, faces):
    kind = os.path.splitext(path)[1]
    if kind == '.obj':
        lines = ['v %r %r %r' % tuple(v) for v in vertices] + ['f %d %d %d' % tuple(f + 1) for f in faces]
    elif kind == '.stl':
        # Binary, as CAD programs write STL.
        records = np.zeros(len(faces), dtype=[('normal', '<f4', 3), ('corners', '<f4', (3, 3)),
                                              ('attributes', '<u2')])
        records['corners'] = vertices[faces]
        with open(path, 'wb') as stream:
            stream.write(b'bench'.ljust(80) + np.uint32(len(faces)).tobytes() + records.tobytes())
        return
    else:
        lines = ['<?xml version="1.0"?>',
                 '<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">',
                 '<asset><unit meter="1"/><up_axis>Z_UP</up_axis></asset><library_geometries>'
                 '<geometry id="g"><mesh><source id="p"><float_array id="pa" count="%d">%s</float_array>'
                 % (vertices.size, ' '.join('%r' % float(v) for v in vertices.ravel())),
                 '<technique_common><accessor source="#pa" count="%d" stride="3"><param name="X" '
                 'type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>'
                 '</accessor></technique_common></source><vertices id="v"><input semantic="POSITION" '
                 'source="#p"/></vertices><triangles count="%d"><input semantic="VERTEX" source="#v" '
                 'offset="0"/><p>%s</p></triangles></mesh></geometry></library_geometries>'
                 % (len(vertices), len(faces), ' '.join(str(int(i)) for i in faces.ravel())),
                 '<library_visual_scenes><visual_scene id="s"><node><instance_geometry url="#g"/>'
                 '</node></visual_scene></library_visual_scenes><scene><instance_visual_scene '
                 'url="#s"/></scene></COLLADA>']
    with open(path, 'w') as stream:
        stream.write('\n'.join(lines) + '\n')


def make_world(folder, models):
    shapes = {'table.stl': table(), 'table.dae': table((0.9, 0.9, 0.04)), 'chair.obj': chair(),
              'chair.dae': chair(), 'chair.stl': chair(), 'torus_small.obj': torus(24, 12),
              'torus_large.stl': torus(100, 50), 'torus_large.dae': torus(100, 50),
              'sphere_small.stl': sphere(20, 10), 'sphere_large.obj': sphere(100, 100),
              'bowl.dae': sphere(40, 20, 0.2, 0.2), 'cabinet.obj': box((0.6, 0.4, 1.8), (0, 0, 0.9))}
    for name, (vertices, faces) in shapes.items():
        write(os.path.join(folder, name), vertices, faces)
    names = sorted(shapes)
    body = []
    for index in range(models):
        x, y = (index % 12) * 2.0 - 11, (index // 12) * 2.0 - 11
        body.append('<model name="m%d"><static>1</static><pose>%g %g 0 0 0 %g</pose><link name="l">'
                    '<visual name="v"><geometry><mesh><uri>file://%s</uri></mesh></geometry></visual>'
                    '</link></model>' % (index, x, y, 0.1 * index,
                                         os.path.join(folder, names[index % len(names)])))
    triangles = sum(len(faces) for _, faces in shapes.values())
    path = os.path.join(folder, 'meshes.world')
    with open(path, 'w') as stream:
        stream.write('<sdf version="1.6"><world name="meshes">%s</world></sdf>' % ''.join(body))
    return path, len(shapes), triangles


def one_process(world):
    """In a fresh process, (wall s, CPU s) of: importing, the first load, the second load; and
    the scene's primitives and the records of what was left out."""
    code = '''
import json, sys, time
sys.path.insert(0, %r)
import numpy
import flatsim.loading.meshes, flatsim.world.sim
from flatsim.loading.sdf_world import load_world
from flatsim.world.sim import Simulation
def timed(action):
    wall, cpu = time.perf_counter(), time.process_time()
    result = action()
    return (time.perf_counter() - wall, time.process_time() - cpu), result
def start():
    import trimesh
    flatsim.loading.meshes.piece_finder()(numpy.zeros((1, 3), dtype=numpy.int64), 1)
imported, _ = timed(start)
first, sim = timed(lambda: Simulation(load_world(%r)))
second, _ = timed(lambda: Simulation(load_world(%r)))
print(json.dumps([imported, first, second, len(sim.scene), len(sim.skipped)]))
''' % (SOURCE, world, world)
    out = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--models', type=int, default=120)
    parser.add_argument('--repeat', type=int, default=3)
    args = parser.parse_args()
    if args.models < 1 or args.repeat < 1:
        parser.error('--models and --repeat must be at least 1')
    with tempfile.TemporaryDirectory(prefix='bench_meshes_') as folder:
        world, files, triangles = make_world(folder, args.models)
        runs = [one_process(world) for _ in range(args.repeat)]
    imported, first, second, prims, skipped = zip(*runs)
    print('world: %d models on %d mesh files (%d triangles in all): %d scene primitives, %d skipped'
          % (args.models, files, triangles, prims[0], skipped[0]))

    def figure(pairs):
        return '%.3f s wall, %.3f s CPU' % (statistics.median(p[0] for p in pairs),
                                            statistics.median(p[1] for p in pairs))
    print('import trimesh, load the compiled piece finder (once per process): %s' % figure(imported))
    print('first load, every file read and covered: %s' % figure(first))
    print('the same world again, files kept: %s' % figure(second))
    print('(medians of %d fresh processes)' % args.repeat)


if __name__ == '__main__':
    main()
