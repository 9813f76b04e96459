// Three.js objects for the scene's models: one group per model, one per link,
// a mesh per shape, and each camera's field of view as a cone of lines.

import * as THREE from 'three';

// How far a camera's field of view is drawn (m), as the overhead view draws it.
const CONE_LENGTH = 3.0;

function setPose(object, pose) {
  object.position.set(pose[0], pose[1], pose[2]);
  object.rotation.set(pose[3], pose[4], pose[5], 'ZYX');
}

function geometryOf(shape) {
  const size = shape.size;
  if (shape.shape === 'box') return new THREE.BoxGeometry(size[0], size[1], size[2]);
  if (shape.shape === 'cylinder') {
    // SDF's cylinders stand along z, three.js's along y.
    return new THREE.CylinderGeometry(size[0], size[0], size[1], 32).rotateX(Math.PI / 2);
  }
  return new THREE.SphereGeometry(size[0], 32, 16);
}

function meshOf(shape) {
  const [r, g, b, a] = shape.color;
  const material = new THREE.MeshLambertMaterial({color: new THREE.Color(r, g, b),
                                                  transparent: a < 1, opacity: a});
  const mesh = new THREE.Mesh(geometryOf(shape), material);
  mesh.name = shape.name;
  setPose(mesh, shape.pose);
  return mesh;
}

// A link's collision shapes as Gazebo's View > Collisions draws them: translucent orange.
export function buildCollisions(name, shapes) {
  const group = new THREE.Group();
  group.name = name;
  for (const shape of shapes) {
    const mesh = new THREE.Mesh(geometryOf(shape), new THREE.MeshBasicMaterial(
      {color: 0xff8000, transparent: true, opacity: 0.5, depthWrite: false}));
    mesh.name = shape.name;
    mesh.userData.collision = true;
    setPose(mesh, shape.pose);
    group.add(mesh);
  }
  return group;
}

// Lines from the camera's origin to the corners of its image at CONE_LENGTH along +x.
export function cameraCone(sensor) {
  const length = Math.min(CONE_LENGTH, sensor.far || CONE_LENGTH);
  const halfWidth = length * Math.tan(sensor.hfov / 2);
  const halfHeight = halfWidth * sensor.height / sensor.width;
  const corners = [[length, halfWidth, halfHeight], [length, -halfWidth, halfHeight],
                   [length, -halfWidth, -halfHeight], [length, halfWidth, -halfHeight]];
  const points = [];
  corners.forEach((corner, index) => {
    const next = corners[(index + 1) % corners.length];
    points.push(0, 0, 0, ...corner, ...corner, ...next);
  });
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.Float32BufferAttribute(points, 3));
  const cone = new THREE.LineSegments(geometry, new THREE.LineBasicMaterial({color: 0xffe060}));
  cone.name = 'field of view of ' + sensor.name;
  setPose(cone, sensor.pose);
  return cone;
}

export function buildModel(description) {
  const group = new THREE.Group();
  group.name = description.name;
  group.userData.name = description.name;
  setPose(group, description.pose);
  const links = new Map();
  for (const link of description.links) {
    const linkGroup = new THREE.Group();
    linkGroup.name = description.name + '::' + link.name;
    setPose(linkGroup, link.pose);
    for (const shape of link.shapes) linkGroup.add(meshOf(shape));
    links.set(link.name, linkGroup);
    group.add(linkGroup);
  }
  const cones = [];
  for (const sensor of description.sensors) {
    if (sensor.kind !== 'camera') continue;
    const cone = cameraCone(sensor);
    (links.get(sensor.link) || group).add(cone);
    cones.push(cone);
  }
  return {group, links, cones, description};
}
