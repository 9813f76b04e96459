// The view's light, and the same light baked into colours for what never moves.
//
// A browser without a GPU shades every pixel on the CPU, one it may share with
// the simulator. The world's static models (walls, furniture) and the floor
// never move, so their shading is computed once here, as three.js's Lambert
// shader would compute it for these lights, and drawn unlit: the static models
// as one mesh with a colour per vertex (one draw call instead of one per
// shape), the floor in one flat colour. What moves (robots, balls) keeps
// three.js's lit material, so its faces still darken as it turns from the sun.

import * as THREE from 'three';
import {mergeGeometries} from 'three/addons/utils/BufferGeometryUtils.js';

const SKY = new THREE.Color(0xffffff);
const GROUND = new THREE.Color(0x444444);
const SKY_INTENSITY = 1.6;
const SUN_INTENSITY = 1.6;
const SUN_POSITION = new THREE.Vector3(-3, -5, 10);
const SUN_DIRECTION = SUN_POSITION.clone().normalize();

export function addLights(scene) {
  // Built while DEFAULT_UP is +z, so its sky is overhead.
  scene.add(new THREE.HemisphereLight(SKY, GROUND, SKY_INTENSITY));
  const sun = new THREE.DirectionalLight(0xffffff, SUN_INTENSITY);
  sun.position.copy(SUN_POSITION);
  scene.add(sun);
}

// What Lambert's shader outputs (linear) for a surface of colour albedo facing normal (world).
export function litColor(albedo, normal, target = new THREE.Color()) {
  const skyWeight = 0.5 * normal.z + 0.5;
  const sun = Math.max(0, normal.dot(SUN_DIRECTION)) * SUN_INTENSITY;
  target.copy(GROUND).lerp(SKY, skyWeight).multiplyScalar(SKY_INTENSITY);
  target.r += sun;
  target.g += sun;
  target.b += sun;
  return target.multiply(albedo).multiplyScalar(1 / Math.PI);
}

// The floor: a horizontal plane of colour albedo, lit as above, in one flat colour.
export function floorColor(albedo) {
  return litColor(albedo, new THREE.Vector3(0, 0, 1));
}

// One unlit mesh with the opaque meshes under groups, in world coordinates, each
// vertex coloured as the light shades it. null when there are none.
export function bakeStatic(groups) {
  const parts = [];
  const normal = new THREE.Vector3();
  const color = new THREE.Color();
  for (const group of groups) {
    group.updateMatrixWorld(true);
    group.traverse((object) => {
      if (!object.isMesh || object.material.transparent) return;
      // applyMatrix4 turns the normals too.
      const geometry = object.geometry.clone().applyMatrix4(object.matrixWorld);
      const normals = geometry.getAttribute('normal');
      const colors = new Float32Array(normals.count * 3);
      for (let index = 0; index < normals.count; index += 1) {
        normal.fromBufferAttribute(normals, index).normalize();
        litColor(object.material.color, normal, color).toArray(colors, index * 3);
      }
      geometry.setAttribute('color', new THREE.BufferAttribute(colors, 3));
      geometry.deleteAttribute('uv');
      parts.push(geometry);
    });
  }
  if (parts.length === 0) return null;
  const merged = mergeGeometries(parts);
  for (const part of parts) part.dispose();
  merged.deleteAttribute('normal');
  const mesh = new THREE.Mesh(merged, new THREE.MeshBasicMaterial({vertexColors: true}));
  mesh.name = 'static models';
  return mesh;
}
