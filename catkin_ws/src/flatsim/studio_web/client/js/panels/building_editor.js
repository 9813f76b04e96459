// Gazebo's Building Editor (Edit > Building Editor, Ctrl+B): walls drawn from above on a
// grid, segment by segment (click, click, ...; double-click or Esc ends the chain, as does
// coming back to where it started), each end snapped to another wall's end nearby or else
// to the grid, by flatsim.authoring.building's rule (the simulator applies it again on Save).
// Doors and windows go on a wall where it is clicked. A wall's or an opening's inspector
// edits its sizes; the simulator checks them on Save and says what is wrong. Saved as a
// static model in ~/building_editor_models/NAME; Exit puts it into the world where it was drawn.

import {EditorShell} from './editor_shell.js';
import {colourInput, labelledInput, makeButton, numberInput} from './dialogs.js';

// flatsim.authoring.building: GRID_STEP, END_SNAP_RADIUS and Gazebo's defaults.
const GRID_STEP = 0.25;
const END_SNAP_RADIUS = 0.25;
const WALL = {thickness: 0.15, height: 2.5, color: [1, 1, 1, 1]};
const OPENINGS = {door: {width: 0.9, height: 2.0, elevation: 0},
                  window: {width: 0.8, height: 0.8, elevation: 0.5}};
// A click within this distance of a wall's face (m) picks the wall, or puts a door on it.
const PICK_REACH = 0.25;
const START_SCALE = 50;          // pixels per metre
const MIN_SCALE = 5;
const MAX_SCALE = 400;
// A press that moves further than this (pixels) pans the drawing instead of clicking.
const CLICK_SLOP = 4;
// The models' names on the drawing: a line's height (pixels), and how many lines one may go down.
const LABEL_HEIGHT = 13;
const LABEL_LINES = 4;

// Where a drawn point lands: the nearest end of another wall within END_SNAP_RADIUS, else
// the nearest grid point (flatsim.authoring.building.snap_point).
export function snapPoint(point, walls, skip = -1) {
  let best = null;
  let bestDistance = END_SNAP_RADIUS;
  walls.forEach((wall, index) => {
    if (index === skip) return;
    for (const end of [wall.start, wall.end]) {
      const distance = Math.hypot(end[0] - point[0], end[1] - point[1]);
      if (distance <= bestDistance) {
        best = [end[0], end[1]];
        bestDistance = distance;
      }
    }
  });
  return best || point.map((value) => Math.round(value / GRID_STEP) * GRID_STEP);
}

// The names the simulator gives the walls and openings (flatsim.authoring.building), which its
// refusals use: shown on the drawing and in the inspectors, so that a refused part can be found.
export const wallName = (index) => 'Wall_' + index;
export const openingName = (opening) => opening.kind + ' on ' + wallName(opening.wall);

const same = (a, b) => Math.abs(a[0] - b[0]) < 1e-9 && Math.abs(a[1] - b[1]) < 1e-9;
const wallLength = (wall) => Math.hypot(wall.end[0] - wall.start[0], wall.end[1] - wall.start[1]);
const round = (value, digits = 3) => Number(value.toFixed(digits));

// (distance from the wall's centre line, offset along it from its start) of a point.
function alongWall(wall, point) {
  const length = wallLength(wall) || 1e-9;
  const ux = (wall.end[0] - wall.start[0]) / length;
  const uy = (wall.end[1] - wall.start[1]) / length;
  const dx = point[0] - wall.start[0];
  const dy = point[1] - wall.start[1];
  const offset = dx * ux + dy * uy;
  const clamped = Math.max(0, Math.min(length, offset));
  const distance = Math.hypot(dx - clamped * ux, dy - clamped * uy);
  return {distance, offset};
}

function heading(text) {
  const element = document.createElement('h2');
  element.textContent = text;
  return element;
}

export function mount(studio) {
  const section = studio.view.canvas.parentElement;
  const canvas = document.createElement('canvas');
  canvas.className = 'building-canvas';
  canvas.hidden = true;
  canvas.tabIndex = 0;
  canvas.setAttribute('aria-label', 'Building Editor drawing: the floor from above, 0.25 m grid');
  section.append(canvas);
  const context = canvas.getContext('2d');

  let design = null;
  let tool = 'select';
  let chain = null;               // {first, last}: the point the next click draws a wall to
  let hover = null;
  let selection = null;           // {kind: 'wall' | 'opening', index}
  let centre = [0, 0];
  let labels = [];                // the models' names as drawn last
  let wallLabels = [];            // the walls' names as drawn last
  let scale = START_SCALE;
  let pressed = null;

  // -- the palette -----------------------------------------------------------------------
  const palette = document.createElement('section');
  const tools = new Map();
  const toolButton = (name, label, title) => {
    const button = makeButton(label, () => setTool(tool === name ? 'select' : name), title);
    button.setAttribute('aria-pressed', 'false');
    tools.set(name, button);
    return button;
  };
  const walls = document.createElement('div');
  walls.className = 'button-row';
  walls.append(toolButton('wall', 'Wall', 'Draw walls: click, click, ...; back at the first corner '
                          + 'closes the loop; double-click or Esc ends; Shift places off the grid'));
  const features = document.createElement('div');
  features.className = 'button-row';
  features.append(toolButton('window', 'Window', 'Click on a wall to put a window there'),
                  toolButton('door', 'Door', 'Click on a wall to put a door there'));
  const [nameLabel, nameInput] = labelledInput('Model name', {id: 'building-editor-name'});
  nameInput.addEventListener('change', () => { design.name = nameInput.value; shell.changed(); });
  const nameForm = document.createElement('div');
  nameForm.className = 'form';
  nameForm.append(nameLabel, nameInput);
  const hint = document.createElement('p');
  hint.className = 'hint';
  hint.setAttribute('role', 'status');
  hint.setAttribute('aria-label', 'Building Editor hint');
  const inspector = document.createElement('div');
  inspector.className = 'inspector';
  inspector.setAttribute('role', 'group');
  palette.append(heading('Create Walls'), walls, heading('Add Features'), features, nameForm, hint, inspector);

  const shell = new EditorShell(studio, {
    title: 'Building Editor', kind: 'building', command: 'save_building', defaultFolder: 'building_folder',
    palette, name: () => design.name,
    design: () => ({walls: design.walls.map((wall) => ({...wall})),
                    openings: design.openings.map((opening) => ({...opening}))}),
    savedAs: (reply) => {
      reply.walls.forEach((snapped, index) => Object.assign(design.walls[index], snapped));
      design.name = shell.saved.name;
      nameInput.value = design.name;
      draw();
    },
    reset, opened: () => { canvas.hidden = false; reset(); resize(); canvas.focus(); },
    closed: () => { canvas.hidden = true; },
  });

  function reset() {
    design = {name: 'Untitled', walls: [], openings: []};
    nameInput.value = design.name;
    chain = null;
    selection = null;
    setTool('select');
  }

  function setTool(name) {
    tool = name;
    if (name !== 'wall') chain = null;
    for (const [key, button] of tools) button.setAttribute('aria-pressed', String(key === name));
    hint.textContent = {
      select: 'Click a wall, door or window to edit it; the mouse wheel zooms, a drag moves the view',
      wall: chain ? 'Click to end this wall and start the next; click the first corner to close the '
                    + 'loop; double-click or Esc ends the chain; Shift places off the grid'
                  : 'Click where the wall starts',
      door: 'Click on a wall to put a door there', window: 'Click on a wall to put a window there',
    }[name];
    canvas.classList.toggle('drawing', name !== 'select');
    showInspector();
    draw();
  }

  // -- from the floor to the canvas and back ------------------------------------------------
  const toCanvas = ([x, y]) => [canvas.width / 2 + (x - centre[0]) * scale,
                                canvas.height / 2 - (y - centre[1]) * scale];
  const toFloor = (px, py) => [centre[0] + (px - canvas.width / 2) / scale,
                               centre[1] - (py - canvas.height / 2) / scale];
  const eventPoint = (event) => {
    const rect = canvas.getBoundingClientRect();
    return toFloor((event.clientX - rect.left) * canvas.width / rect.width,
                   (event.clientY - rect.top) * canvas.height / rect.height);
  };

  function resize() {
    canvas.width = section.clientWidth || 1;
    canvas.height = section.clientHeight || 1;
    draw();
  }
  new ResizeObserver(() => { if (!canvas.hidden) resize(); }).observe(section);

  // -- drawing -------------------------------------------------------------------------
  const channel = (value) => Math.round(255 * Math.min(1, Math.max(0, value)));
  const rgb = (color) => 'rgb(' + color.slice(0, 3).map(channel).join(',') + ')';

  function segment(from, to, width, style) {
    const [x1, y1] = toCanvas(from);
    const [x2, y2] = toCanvas(to);
    context.strokeStyle = style;
    context.lineWidth = width;
    context.beginPath();
    context.moveTo(x1, y1);
    context.lineTo(x2, y2);
    context.stroke();
  }

  function openingEnds(opening) {
    const wall = design.walls[opening.wall];
    const length = wallLength(wall) || 1e-9;
    const at = (offset) => [wall.start[0] + (wall.end[0] - wall.start[0]) * offset / length,
                            wall.start[1] + (wall.end[1] - wall.start[1]) * offset / length];
    return [at(opening.offset - opening.width / 2), at(opening.offset + opening.width / 2)];
  }

  function draw() {
    if (canvas.hidden || !design) return;
    context.fillStyle = '#1d2126';
    context.fillRect(0, 0, canvas.width, canvas.height);
    const [left, top] = toFloor(0, 0);
    const [right, bottom] = toFloor(canvas.width, canvas.height);
    const step = scale * GRID_STEP >= 6 ? GRID_STEP : 1;
    for (let x = Math.ceil(left / step) * step; x <= right; x += step) {
      segment([x, bottom], [x, top], 1, Math.abs(x - Math.round(x)) < 1e-6 ? '#3e4650' : '#2a3037');
    }
    for (let y = Math.ceil(bottom / step) * step; y <= top; y += step) {
      segment([left, y], [right, y], 1, Math.abs(y - Math.round(y)) < 1e-6 ? '#3e4650' : '#2a3037');
    }
    segment([0, bottom], [0, top], 1, '#4f6e4f');
    segment([left, 0], [right, 0], 1, '#6e4f4f');
    // The world's models, so that the building goes where it should; a name that would run
    // into one drawn already goes a line lower, or is left out when no line is free.
    context.font = '11px system-ui, sans-serif';
    labels = [];
    for (const [name, pose] of Object.entries(studio.poses)) {
      const [x, y] = toCanvas(pose);
      context.fillStyle = '#7f8a96';
      context.fillRect(x - 2, y - 2, 4, 4);
      const width = context.measureText(name).width;
      for (let line = 0; line < LABEL_LINES; line += 1) {
        const box = {name, x: x + 5, y: y - 4 - LABEL_HEIGHT + 2 + line * LABEL_HEIGHT, width,
                     height: LABEL_HEIGHT};
        const clashes = labels.some((other) => box.x < other.x + other.width && other.x < box.x + box.width
                                    && box.y < other.y + other.height && other.y < box.y + box.height);
        if (clashes) continue;
        context.fillText(name, box.x, box.y + LABEL_HEIGHT - 2);
        labels.push(box);
        break;
      }
    }
    design.walls.forEach((wall, index) => {
      const chosen = selection && selection.kind === 'wall' && selection.index === index;
      segment(wall.start, wall.end, Math.max(2, wall.thickness * scale) + (chosen ? 4 : 0),
              chosen ? '#f39c12' : rgb(wall.color));
    });
    design.openings.forEach((opening, index) => {
      const wall = design.walls[opening.wall];
      const [from, to] = openingEnds(opening);
      const chosen = selection && selection.kind === 'opening' && selection.index === index;
      segment(from, to, Math.max(2, wall.thickness * scale) + 2,
              chosen ? '#f39c12' : (opening.kind === 'door' ? '#a0672d' : '#5dade2'));
    });
    // Each wall's name at its middle, across it.
    wallLabels = [];
    context.font = 'bold 11px system-ui, sans-serif';
    design.walls.forEach((wall, index) => {
      const name = wallName(index);
      const [x, y] = toCanvas([(wall.start[0] + wall.end[0]) / 2, (wall.start[1] + wall.end[1]) / 2]);
      const width = context.measureText(name).width;
      const box = {name, x: x - width / 2, y: y - LABEL_HEIGHT / 2, width, height: LABEL_HEIGHT};
      context.fillStyle = 'rgba(29,33,38,0.8)';
      context.fillRect(box.x - 2, box.y, box.width + 4, box.height);
      context.fillStyle = '#ffd27f';
      context.fillText(name, box.x, box.y + LABEL_HEIGHT - 2);
      wallLabels.push(box);
    });
    context.font = '11px system-ui, sans-serif';
    if (tool === 'wall' && hover) {
      if (chain) {
        segment(chain.last, hover, Math.max(2, WALL.thickness * scale), 'rgba(243,156,18,0.6)');
        // The wall's length as it is drawn, beside its middle, as Gazebo shows it.
        const [mx, my] = toCanvas([(chain.last[0] + hover[0]) / 2, (chain.last[1] + hover[1]) / 2]);
        context.fillStyle = '#f39c12';
        context.fillText(drawnLength() + ' m', mx + 8, my - 8);
      }
      const [x, y] = toCanvas(hover);
      context.strokeStyle = '#f39c12';
      context.lineWidth = 2;
      context.strokeRect(x - 4, y - 4, 8, 8);
    }
  }

  // -- the mouse -------------------------------------------------------------------------
  // Shift releases the snap: the point goes where the mouse is, to the millimetre.
  const placed = (point, free) => (free ? point.map((value) => round(value)) : snapPoint(point, design.walls));

  // The length of the wall being drawn, to the centimetre, or null.
  const drawnLength = () => (chain && hover ? round(wallLength({start: chain.last, end: hover}), 2) : null);

  function showDrawnLength() {
    const length = drawnLength();
    const base = hint.textContent.split(' \u2014 ')[0];
    hint.textContent = length === null ? base : base + ' \u2014 this wall: ' + length + ' m';
  }

  function clickAt(point, free = false) {
    if (tool === 'wall') return drawTo(placed(point, free));
    if (tool === 'door' || tool === 'window') return putOpening(tool, point);
    selection = pick(point);
    showInspector();
    draw();
  }

  function drawTo(point) {
    if (!chain) {
      chain = {first: point, last: point};
    } else if (!same(point, chain.last)) {
      design.walls.push({start: chain.last, end: point, ...WALL, color: [...WALL.color]});
      shell.changed();
      chain.last = point;
      if (same(point, chain.first)) chain = null;
    }
    setTool('wall');
  }

  function nearestWall(point) {
    let best = null;
    design.walls.forEach((wall, index) => {
      const {distance, offset} = alongWall(wall, point);
      if (distance <= wall.thickness / 2 + PICK_REACH && (!best || distance < best.distance)) {
        best = {index, distance, offset};
      }
    });
    return best;
  }

  function pick(point) {
    const opening = design.openings.findIndex((candidate) => {
      const {distance, offset} = alongWall(design.walls[candidate.wall], point);
      return distance <= design.walls[candidate.wall].thickness / 2 + PICK_REACH &&
             Math.abs(offset - candidate.offset) <= candidate.width / 2;
    });
    if (opening >= 0) return {kind: 'opening', index: opening};
    const wall = nearestWall(point);
    return wall ? {kind: 'wall', index: wall.index} : null;
  }

  function putOpening(kind, point) {
    const wall = nearestWall(point);
    if (!wall) return studio.notify('Click on a wall to put a ' + kind + ' there');
    const sizes = OPENINGS[kind];
    const length = wallLength(design.walls[wall.index]);
    const offset = Math.max(sizes.width / 2, Math.min(length - sizes.width / 2, wall.offset));
    design.openings.push({wall: wall.index, offset: round(offset), kind, ...sizes});
    selection = {kind: 'opening', index: design.openings.length - 1};
    shell.changed();
    setTool('select');
  }

  canvas.addEventListener('pointerdown', (event) => {
    pressed = {x: event.clientX, y: event.clientY, centre: [...centre]};
    canvas.setPointerCapture(event.pointerId);
  });
  canvas.addEventListener('pointermove', (event) => {
    if (pressed && Math.hypot(event.clientX - pressed.x, event.clientY - pressed.y) > CLICK_SLOP) {
      centre = [pressed.centre[0] - (event.clientX - pressed.x) / scale,
                pressed.centre[1] + (event.clientY - pressed.y) / scale];
    }
    hover = tool === 'wall' ? placed(eventPoint(event), event.shiftKey) : null;
    if (tool === 'wall') showDrawnLength();
    draw();
  });
  canvas.addEventListener('pointerup', (event) => {
    const down = pressed;
    pressed = null;
    if (!down || event.button !== 0) return;
    if (Math.hypot(event.clientX - down.x, event.clientY - down.y) > CLICK_SLOP) return;
    clickAt(eventPoint(event), event.shiftKey);
  });
  canvas.addEventListener('dblclick', () => {
    if (chain) setTool('select');
  });
  canvas.addEventListener('wheel', (event) => {
    event.preventDefault();
    const before = eventPoint(event);
    scale = Math.min(MAX_SCALE, Math.max(MIN_SCALE, scale * Math.exp(-event.deltaY / 500)));
    const after = eventPoint(event);
    centre = [centre[0] + before[0] - after[0], centre[1] + before[1] - after[1]];
    draw();
  }, {passive: false});
  // Closing or reloading the tab would lose a design not saved: the browser asks first.
  window.addEventListener('beforeunload', (event) => {
    if (!shell.active || !shell.dirty) return;
    event.preventDefault();
    event.returnValue = '';
  });
  window.addEventListener('keydown', (event) => {
    if (!shell.active || document.querySelector('dialog[open]')) return;
    const editing = event.target instanceof HTMLInputElement;
    if (event.key === 'Escape') {
      setTool('select');
    } else if (event.key === 'Delete' && !editing && selection) {
      removeSelected();
    } else {
      return;
    }
    // The world's own keys (Delete deletes the selected model) wait while the editor is open.
    event.preventDefault();
    event.stopPropagation();
  }, true);
  studio.on('poses', () => { if (shell.active) draw(); });

  // -- the inspectors --------------------------------------------------------------------
  function removeSelected() {
    if (selection.kind === 'wall') {
      const gone = selection.index;
      design.walls.splice(gone, 1);
      design.openings = design.openings.filter((opening) => opening.wall !== gone)
        .map((opening) => ({...opening, wall: opening.wall > gone ? opening.wall - 1 : opening.wall}));
    } else {
      design.openings.splice(selection.index, 1);
    }
    selection = null;
    shell.changed();
    showInspector();
    draw();
  }

  // A field of the inspector, with its unit after it (every size here is in metres).
  const numberField = (label, read, write) => {
    const [labelElement, input] = numberInput(studio, label, read, (value) => {
      if (value === null) return showInspector();
      write(value);
      shell.changed();
      showInspector();
      draw();
    });
    const cell = document.createElement('span');
    cell.className = 'with-unit';
    const unit = document.createElement('span');
    unit.className = 'unit';
    unit.textContent = 'm';
    cell.append(input, unit);
    return [labelElement, cell];
  };

  function showInspector() {
    const item = selection && (selection.kind === 'wall' ? design.walls : design.openings)[selection.index];
    inspector.hidden = !item;
    if (!item) return inspector.replaceChildren();
    const form = document.createElement('div');
    form.className = 'form';
    let title;
    const partName = document.createElement('output');
    partName.id = 'building-part-name';
    partName.value = selection.kind === 'wall' ? wallName(selection.index) : openingName(item);
    const partLabel = document.createElement('label');
    partLabel.textContent = 'Name';
    partLabel.htmlFor = partName.id;
    form.append(partLabel, partName);
    if (selection.kind === 'wall') {
      title = 'Wall Inspector';
      const point = (key, axis) => numberField((key === 'start' ? 'Start ' : 'End ') + 'XY'[axis],
                                               () => item[key][axis], (value) => {
        item[key] = axis === 0 ? [value, item[key][1]] : [item[key][0], value];
      });
      const length = document.createElement('output');
      length.id = 'building-wall-length';
      length.value = round(wallLength(item)) + ' m';
      const lengthLabel = document.createElement('label');
      lengthLabel.textContent = 'Length';
      lengthLabel.htmlFor = length.id;
      const colour = colourInput(studio, 'Color', () => item.color, (values) => {
        item.color = values;
        shell.changed();
        draw();
      });
      form.append(...point('start', 0), ...point('start', 1), ...point('end', 0), ...point('end', 1),
                  lengthLabel, length,
                  ...numberField('Height', () => item.height, (value) => { item.height = value; }),
                  ...numberField('Thickness', () => item.thickness, (value) => { item.thickness = value; }),
                  ...colour);
    } else {
      title = item.kind === 'door' ? 'Door Inspector' : 'Window Inspector';
      form.append(...numberField('Position', () => item.offset, (value) => { item.offset = value; }),
                  ...numberField('Width', () => item.width, (value) => { item.width = value; }),
                  ...numberField('Height', () => item.height, (value) => { item.height = value; }),
                  ...numberField('Elevation', () => item.elevation, (value) => { item.elevation = value; }));
    }
    inspector.setAttribute('aria-label', title);
    inspector.replaceChildren(heading(title), form, makeButton('Delete', removeSelected));
  }

  reset();
  studio.buildingEditor = {
    shell,
    get design() { return design; },
    // The models' names as drawn last: {name, x, y, width, height} in canvas pixels.
    get labels() { return labels; },
    // The walls' names as drawn last, in the same form.
    get wallLabels() { return wallLabels; },
    // Where the floor point (x, y) is on the screen, for tests that draw with the mouse.
    screenPoint(x, y) {
      const rect = canvas.getBoundingClientRect();
      const [px, py] = toCanvas([x, y]);
      return {x: rect.left + px * rect.width / canvas.width, y: rect.top + py * rect.height / canvas.height};
    },
  };
  studio.menus.add('Edit', {label: 'Building Editor', shortcut: 'Ctrl+B', action: () => shell.open()});
  window.addEventListener('keydown', (event) => {
    if ((event.ctrlKey || event.metaKey) && event.key.toLowerCase() === 'b' && !event.shiftKey) {
      event.preventDefault();
      shell.open();
    }
  });
}
