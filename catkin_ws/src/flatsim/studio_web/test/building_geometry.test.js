// The Building Editor's geometry and Undo history, without a page: node --test test/
// (tests/test_studio_building_geometry.py runs it with the project's tests).
import {test} from 'node:test';
import assert from 'node:assert/strict';

import * as geometry from '../client/js/building/geometry.js';
import {Drawing, History} from '../client/js/building/drawing.js';

// As flatsim.authoring.building.editor_settings gives them.
const SETTINGS = {grid_step: 0.25, snap_radius: 0.25, min_length: 0.001, max_size: 1000, max_parts: 500,
                  wall: {thickness: 0.15, height: 2.5, color: [1, 1, 1, 1]},
                  door: {width: 0.9, height: 2.0, elevation: 0},
                  window: {width: 0.8, height: 0.8, elevation: 0.5}};
const WALL = (start, end) => geometry.newWall(start, end, SETTINGS);

test('a point lands on the grid, by the grid step it is given', () => {
  assert.deepEqual(geometry.snapPoint([0.13, 0.37], [], SETTINGS), [0.25, 0.25]);
  assert.deepEqual(geometry.snapPoint([1.1, -0.6], [], {...SETTINGS, grid_step: 0.5}), [1, -0.5]);
  // No float dust: 0.3 is 0.3, not 0.30000000000000004.
  assert.deepEqual(geometry.snapToGrid([0.31, 0.29], 0.1), [0.3, 0.3]);
});

test("a point near another wall's end lands on it, within the snap radius only", () => {
  const walls = [WALL([0, 0], [4.03, 0.02])];
  assert.deepEqual(geometry.snapPoint([4.2, 0.1], walls, SETTINGS), [4.03, 0.02]);
  assert.deepEqual(geometry.snapPoint([4.4, 0.1], walls, SETTINGS), [4.5, 0]);
  assert.deepEqual(geometry.snapPoint([4.4, 0.1], walls, {...SETTINGS, snap_radius: 0.5}), [4.03, 0.02]);
  // A wall skipped does not attract.
  assert.deepEqual(geometry.snapPoint([4.2, 0.1], walls, SETTINGS, 0), [4.25, 0]);
});

test('Shift places the point where the mouse is, to the millimetre', () => {
  const walls = [WALL([0, 0], [1, 0])];
  assert.deepEqual(geometry.placePoint([1.12345, 0.0678], walls, SETTINGS, true), [1.123, 0.068]);
  assert.deepEqual(geometry.placePoint([1.12345, 0.0678], walls, SETTINGS, false), [1, 0]);
});

test('a chain of walls closes its loop back at its first corner, and ends there', () => {
  const corners = [[0, 0], [3, 0], [3, 2], [0, 2], [0, 0]];
  let chain = null;
  const walls = [];
  const closings = [];
  for (const corner of corners) {
    const step = geometry.drawTo(chain, corner, walls, SETTINGS);
    assert.equal(step.refused, null);
    if (step.wall) walls.push(step.wall);
    closings.push(step.closed);
    chain = step.chain;
  }
  assert.deepEqual(walls.map((wall) => [wall.start, wall.end]),
                   [[[0, 0], [3, 0]], [[3, 0], [3, 2]], [[3, 2], [0, 2]], [[0, 2], [0, 0]]]);
  assert.deepEqual(closings, [false, false, false, false, true]);
  assert.equal(chain, null);
  // A new wall has the defaults it is given.
  assert.equal(walls[0].height, 2.5);
  assert.equal(walls[0].thickness, 0.15);
});

test('a click on the last corner adds no wall of no length', () => {
  const first = geometry.drawTo(null, [1, 1], [], SETTINGS);
  const again = geometry.drawTo(first.chain, [1, 1.0005], [], SETTINGS);
  assert.equal(again.wall, null);
  assert.deepEqual(again.chain, first.chain);
});

test('the limit on walls is refused with what it is', () => {
  const settings = {...SETTINGS, max_parts: 2};
  const walls = [WALL([0, 0], [1, 0]), WALL([1, 0], [1, 1])];
  const step = geometry.drawTo({first: [0, 0], last: [1, 1]}, [0, 1], walls, settings);
  assert.equal(step.wall, null);
  assert.equal(step.refused, 'A building may have 2 walls at most');
  assert.deepEqual(step.chain, {first: [0, 0], last: [1, 1]});
});

test('the length of the wall being drawn, to the centimetre', () => {
  assert.equal(geometry.drawnLength({first: [0, 0], last: [0, 0]}, [3, 4.004]), 5);
  assert.equal(geometry.drawnLength(null, [3, 4]), null);
  assert.equal(geometry.wallLength(WALL([1, 1], [4, 5])), 5);
});

test('a door goes whole onto the wall clicked, moved in from its end', () => {
  const design = {name: 'h', walls: [WALL([0, 0], [4, 0]), WALL([4, 0], [4, 3])], openings: []};
  assert.deepEqual(geometry.newOpening(design, 'door', [2, 0.1], SETTINGS, 0.25).opening,
                   {wall: 0, offset: 2, kind: 'door', width: 0.9, height: 2.0, elevation: 0});
  assert.equal(geometry.newOpening(design, 'window', [3.9, -0.1], SETTINGS, 0.25).opening.offset, 3.6);
  assert.equal(geometry.newOpening(design, 'window', [4.1, 1], SETTINGS, 0.25).opening.wall, 1);
  assert.equal(geometry.newOpening(design, 'door', [2, 1], SETTINGS, 0.25).refused,
               'Click on a wall to put a door there');
});

test('a click picks an opening before its wall, and nothing far from every wall', () => {
  const design = {name: 'h', walls: [WALL([0, 0], [4, 0])],
                  openings: [{wall: 0, offset: 2, kind: 'door', width: 0.9, height: 2, elevation: 0}]};
  assert.deepEqual(geometry.pick(design, [2.2, 0.05], 0.25), {kind: 'opening', index: 0});
  assert.deepEqual(geometry.pick(design, [0.5, 0.05], 0.25), {kind: 'wall', index: 0});
  assert.equal(geometry.pick(design, [0.5, 1], 0.25), null);
});

test("a wall removed takes its openings, and the others' walls are renumbered", () => {
  const design = {name: 'h', walls: [WALL([0, 0], [4, 0]), WALL([4, 0], [4, 3]), WALL([4, 3], [0, 3])],
                  openings: [{wall: 1, offset: 1, kind: 'door'}, {wall: 2, offset: 2, kind: 'window'}]};
  geometry.removeWall(design, 1);
  assert.equal(design.walls.length, 2);
  assert.deepEqual(design.openings, [{wall: 1, offset: 2, kind: 'window'}]);
});

test('Undo puts back each edit in turn and Redo goes forward again', () => {
  const drawing = new Drawing('Untitled');
  drawing.edit((design) => { design.walls.push(WALL([0, 0], [1, 0])); });
  drawing.edit((design) => { design.walls.push(WALL([1, 0], [1, 1])); });
  drawing.edit((design) => { design.walls[0].height = 3; });
  assert.ok(drawing.undo());
  assert.equal(drawing.design.walls[0].height, 2.5);
  assert.ok(drawing.undo());
  assert.equal(drawing.design.walls.length, 1);
  assert.ok(drawing.redo());
  assert.equal(drawing.design.walls.length, 2);
  assert.ok(drawing.redo());
  assert.equal(drawing.design.walls[0].height, 3);
  assert.equal(drawing.redo(), false);
});

test('an edit that changes nothing is no step, and a new edit forgets what could be redone', () => {
  const drawing = new Drawing('Untitled');
  drawing.edit((design) => { design.walls.push(WALL([0, 0], [1, 0])); });
  drawing.edit((design) => { design.walls[0].height = 2.5; });
  assert.equal(drawing.history.past.length, 1);
  drawing.undo();
  drawing.edit((design) => { design.name = 'shed'; });
  assert.equal(drawing.history.canRedo, false);
  assert.equal(drawing.design.walls.length, 0);
  drawing.undo();
  assert.equal(drawing.design.name, 'Untitled');
  assert.equal(drawing.undo(), false);
});

test('the history keeps its last steps only, and a step is a copy, not the state itself', () => {
  const history = new History(2);
  const state = {n: 0};
  for (let n = 0; n < 4; n += 1) {
    state.n = n;
    history.record(state);
  }
  state.n = 4;
  assert.deepEqual(history.undo(state), {n: 3});
  assert.deepEqual(history.undo({n: 3}), {n: 2});
  assert.equal(history.undo({n: 2}), null);
});

test('walls and openings are named as the simulator names them in its refusals', () => {
  assert.equal(geometry.wallName(0), 'Wall_0');
  assert.equal(geometry.wallName(12), 'Wall_12');
  assert.equal(geometry.openingName({kind: 'door', wall: 3, offset: 1}), 'door on Wall_3');
  assert.equal(geometry.openingName({kind: 'window', wall: 0, offset: 1}), 'window on Wall_0');
});
