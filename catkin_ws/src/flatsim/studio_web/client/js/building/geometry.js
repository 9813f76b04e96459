// The Building Editor's geometry, with no page in it: where a drawn point lands (the end of
// another wall nearby, else the grid; Shift: where the mouse is), drawing a chain of walls
// and closing its loop, a wall's length, what a click picks, where a door or a window goes,
// and the limits of a design. It follows flatsim.authoring.building, whose values it is
// given: settings is the hello's `building` (editor_settings() there):
//   {grid_step, snap_radius, min_length, max_size, max_parts,
//    wall: {thickness, height, color}, door: {width, height, elevation}, window: {...}}.
// A design is {name, walls: [{start, end, thickness, height, color}],
//              openings: [{wall, offset, kind, width, height, elevation}]}, points [x, y] in m.

export const round = (value, digits = 3) => Number(value.toFixed(digits));

export const wallLength = (wall) => Math.hypot(wall.end[0] - wall.start[0], wall.end[1] - wall.start[1]);

export const distance = (a, b) => Math.hypot(a[0] - b[0], a[1] - b[1]);

// The names the simulator gives the walls and openings (flatsim.authoring.building), which its
// refusals use: shown on the drawing and in the inspectors, so that a refused part can be found.
export const wallName = (index) => 'Wall_' + index;
export const openingName = (opening) => opening.kind + ' on ' + wallName(opening.wall);

// The grid point nearest to point (flatsim.authoring.building.snap_to_grid).
export function snapToGrid(point, step) {
  return point.map((value) => round(Math.round(value / step) * step, 9));
}

// Where a drawn point lands: the nearest end of another wall within the snap radius, else
// the nearest grid point (flatsim.authoring.building.snap_point). skip: a wall whose ends
// do not attract.
export function snapPoint(point, walls, settings, skip = -1) {
  let best = null;
  let bestDistance = settings.snap_radius;
  walls.forEach((wall, index) => {
    if (index === skip) return;
    for (const end of [wall.start, wall.end]) {
      const away = distance(end, point);
      if (away <= bestDistance) {
        best = [end[0], end[1]];
        bestDistance = away;
      }
    }
  });
  return best || snapToGrid(point, settings.grid_step);
}

// Shift releases the snap: the point goes where the mouse is, to the millimetre.
export function placePoint(point, walls, settings, free = false) {
  return free ? point.map((value) => round(value)) : snapPoint(point, walls, settings);
}

// (distance from the wall's centre line, offset along it from its start) of a point.
export function alongWall(wall, point) {
  const length = wallLength(wall) || 1e-9;
  const ux = (wall.end[0] - wall.start[0]) / length;
  const uy = (wall.end[1] - wall.start[1]) / length;
  const dx = point[0] - wall.start[0];
  const dy = point[1] - wall.start[1];
  const offset = dx * ux + dy * uy;
  const clamped = Math.max(0, Math.min(length, offset));
  return {distance: Math.hypot(dx - clamped * ux, dy - clamped * uy), offset};
}

// The wall whose face is within reach of point, nearest first: {index, distance, offset} or null.
export function nearestWall(walls, point, reach) {
  let best = null;
  walls.forEach((wall, index) => {
    const {distance: away, offset} = alongWall(wall, point);
    if (away <= wall.thickness / 2 + reach && (!best || away < best.distance)) {
      best = {index, distance: away, offset};
    }
  });
  return best;
}

// What a click at point picks: {kind: 'opening' | 'wall', index}, an opening before its wall, or null.
export function pick(design, point, reach) {
  const opening = design.openings.findIndex((candidate) => {
    const wall = design.walls[candidate.wall];
    const {distance: away, offset} = alongWall(wall, point);
    return away <= wall.thickness / 2 + reach && Math.abs(offset - candidate.offset) <= candidate.width / 2;
  });
  if (opening >= 0) return {kind: 'opening', index: opening};
  const wall = nearestWall(design.walls, point, reach);
  return wall ? {kind: 'wall', index: wall.index} : null;
}

// The two ends of an opening on its wall, on the floor.
export function openingEnds(wall, opening) {
  const length = wallLength(wall) || 1e-9;
  const at = (offset) => [wall.start[0] + (wall.end[0] - wall.start[0]) * offset / length,
                          wall.start[1] + (wall.end[1] - wall.start[1]) * offset / length];
  return [at(opening.offset - opening.width / 2), at(opening.offset + opening.width / 2)];
}

// A new wall from start to end, with the editor's defaults.
export function newWall(start, end, settings) {
  const {thickness, height, color} = settings.wall;
  return {start: [...start], end: [...end], thickness, height, color: [...color]};
}

// The length of the wall being drawn (chain's last point to hover), to the centimetre, or null.
export function drawnLength(chain, hover) {
  return chain && hover ? round(distance(chain.last, hover), 2) : null;
}

// A click of the Wall tool at point (placed already). chain is {first, last} while walls
// are being drawn, else null. Returns {chain, wall, closed, refused}: the chain after the
// click; the wall to add, if any; whether it closed the loop (back at the chain's first
// point, which ends the chain); and why no wall was added when one was refused.
export function drawTo(chain, point, walls, settings) {
  if (!chain) return {chain: {first: [...point], last: [...point]}, wall: null, closed: false, refused: null};
  if (distance(point, chain.last) < settings.min_length) return {chain, wall: null, closed: false, refused: null};
  if (walls.length >= settings.max_parts) {
    return {chain, wall: null, closed: false,
            refused: 'A building may have ' + settings.max_parts + ' walls at most'};
  }
  const wall = newWall(chain.last, point, settings);
  const closed = distance(point, chain.first) < settings.min_length;
  return {chain: closed ? null : {first: chain.first, last: [...point]}, wall, closed, refused: null};
}

// A door or a window where point is, on the wall nearest to it: {opening} or {refused}.
// It goes whole onto the wall, its centre moved in from an end when the click was near one.
export function newOpening(design, kind, point, settings, reach) {
  const wall = nearestWall(design.walls, point, reach);
  if (!wall) return {refused: 'Click on a wall to put a ' + kind + ' there'};
  if (design.openings.length >= settings.max_parts) {
    return {refused: 'A building may have ' + settings.max_parts + ' doors and windows at most'};
  }
  const sizes = settings[kind];
  const length = wallLength(design.walls[wall.index]);
  const offset = Math.max(sizes.width / 2, Math.min(length - sizes.width / 2, wall.offset));
  return {opening: {wall: wall.index, offset: round(offset), kind, ...sizes}};
}

// The design without wall index: its openings go with it, the others' wall indices follow.
export function removeWall(design, index) {
  design.walls.splice(index, 1);
  design.openings = design.openings.filter((opening) => opening.wall !== index)
    .map((opening) => ({...opening, wall: opening.wall > index ? opening.wall - 1 : opening.wall}));
}
