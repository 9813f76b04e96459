"""Time flatsim's world loader on a generated Building Editor style world.

Usage: bench_sdf_world.py [MODEL_COUNT]   (default 10000)
Each model is a static two-wall building with materials, plus a <state>
entry with link poses, which is what "Save World As" writes.
"""
import sys
import time

from flatsim.loading.sdf_world import parse_world

WALL = '''
      <link name="Wall_{j}">
        <pose frame="">{j} 0 0 0 0 0</pose>
        <collision name="Wall_{j}_Collision">
          <geometry><box><size>2 0.15 2.5</size></box></geometry>
          <pose frame="">0 0 1.25 0 -0 0</pose>
          <max_contacts>10</max_contacts>
          <surface><contact><ode/></contact><bounce/><friction><torsional><ode/></torsional><ode/></friction></surface>
        </collision>
        <visual name="Wall_{j}_Visual">
          <pose frame="">0 0 1.25 0 -0 0</pose>
          <geometry><box><size>2 0.15 2.5</size></box></geometry>
          <material>
            <script><uri>file://media/materials/scripts/gazebo.material</uri><name>Gazebo/Bricks</name></script>
            <ambient>1 1 1 1</ambient>
          </material>
          <meta><layer>0</layer></meta>
        </visual>
      </link>'''


def generate(count):
    models, states = [], []
    for i in range(count):
        walls = ''.join(WALL.format(j=j) for j in range(2))
        models.append('<model name="building_%d"><static>1</static><pose frame="">%d 0 0 0 0 0</pose>%s'
                      '</model>' % (i, i, walls))
        links = ''.join('<link name="Wall_%d"><pose frame="">%d 1 0 0 0 0</pose></link>' % (j, i + j)
                        for j in range(2))
        states.append('<model name="building_%d"><pose frame="">%d 1 0 0 0 0</pose><scale>1 1 1</scale>%s'
                      '</model>' % (i, i, links))
    return ('<?xml version="1.0" ?><sdf version="1.6"><world name="default">%s<state world_name="default">'
            '%s</state></world></sdf>' % (''.join(models), ''.join(states)))


def main():
    count = int(sys.argv[1]) if len(sys.argv) > 1 else 10000
    text = generate(count)
    start = time.perf_counter()
    world = parse_world(text)
    elapsed = time.perf_counter() - start
    print('%d models, %.1f MB of SDF: loaded in %.2f s (%.0f us per model), %d skipped'
          % (len(world.models), len(text) / 1e6, elapsed, 1e6 * elapsed / max(count, 1), len(world.skipped)))


if __name__ == '__main__':
    main()
