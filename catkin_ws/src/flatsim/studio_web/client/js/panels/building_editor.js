// Gazebo's Building Editor (Edit > Building Editor, Ctrl+B): walls drawn from above on a
// grid, segment by segment (click, click, ...; double-click or Esc ends the chain, as does
// coming back to where it started), each end snapped to another wall's end nearby or else
// to the grid, by flatsim.authoring.building's rule (the simulator applies it again on Save).
// Doors and windows go on a wall where it is clicked. A wall's or an opening's inspector
// edits its sizes; the simulator checks them on Save and says what is wrong. Every edit can
// be undone and redone (Edit > Undo, Ctrl+Z; Edit > Redo, Ctrl+Shift+Z). Saved as a
// static model in ~/building_editor_models/NAME; Exit puts it into the world where it was drawn.
//
// The grid, the snap radius, the defaults and the limits are the simulator's, from its hello
// (studio.settings.building); the geometry is ../building/geometry.js, the design and its
// history ../building/drawing.js, neither of which touches the page.

import {EditorShell, UNTITLED} from './editor_shell.js';
import {colourInput, labelledInput, makeButton, numberInput} from './dialogs.js';
import * as geometry from '../building/geometry.js';
import {Drawing} from '../building/drawing.js';

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
const HINTS = {
  select: 'Click a wall, door or window to edit it; the mouse wheel zooms, a drag moves the view',
  wallStart: 'Click where the wall starts',
  wall: 'Click to end this wall and start the next; click the first corner to close the '
        + 'loop; double-click or Esc ends the chain; Shift places off the grid',
  door: 'Click on a wall to put a door there',
  window: 'Click on a wall to put a window there',
};

function heading(text) {
  const element = document.createElement('h2');
  element.textContent = text;
  return element;
}

const channel = (value) => Math.round(255 * Math.min(1, Math.max(0, value)));
const rgb = (color) => 'rgb(' + color.slice(0, 3).map(channel).join(',') + ')';

// The floor from above on a canvas over the 3D view: where it looks (centre) and how near (scale).
class PlanView {
  constructor(section) {
    this.section = section;
    this.canvas = document.createElement('canvas');
    this.canvas.className = 'building-canvas';
    this.canvas.hidden = true;
    this.canvas.tabIndex = 0;
    section.append(this.canvas);
    this.context = this.canvas.getContext('2d');
    this.centre = [0, 0];
    this.scale = START_SCALE;
  }

  toCanvas([x, y]) {
    return [this.canvas.width / 2 + (x - this.centre[0]) * this.scale,
            this.canvas.height / 2 - (y - this.centre[1]) * this.scale];
  }

  toFloor(px, py) {
    return [this.centre[0] + (px - this.canvas.width / 2) / this.scale,
            this.centre[1] - (py - this.canvas.height / 2) / this.scale];
  }

  eventPoint(event) {
    const rect = this.canvas.getBoundingClientRect();
    return this.toFloor((event.clientX - rect.left) * this.canvas.width / rect.width,
                        (event.clientY - rect.top) * this.canvas.height / rect.height);
  }

  // Where the floor point is on the screen (page pixels).
  screenPoint(x, y) {
    const rect = this.canvas.getBoundingClientRect();
    const [px, py] = this.toCanvas([x, y]);
    return {x: rect.left + px * rect.width / this.canvas.width,
            y: rect.top + py * rect.height / this.canvas.height};
  }

  resize() {
    this.canvas.width = this.section.clientWidth || 1;
    this.canvas.height = this.section.clientHeight || 1;
  }

  // The view dragged by (dx, dy) pixels from where it was (from).
  pan(from, dx, dy) {
    this.centre = [from[0] - dx / this.scale, from[1] + dy / this.scale];
  }

  // The wheel zooms about the point under the mouse.
  zoom(event) {
    const before = this.eventPoint(event);
    this.scale = Math.min(MAX_SCALE, Math.max(MIN_SCALE, this.scale * Math.exp(-event.deltaY / 500)));
    const after = this.eventPoint(event);
    this.centre = [this.centre[0] + before[0] - after[0], this.centre[1] + before[1] - after[1]];
  }

  segment(from, to, width, style) {
    const [x1, y1] = this.toCanvas(from);
    const [x2, y2] = this.toCanvas(to);
    const context = this.context;
    context.strokeStyle = style;
    context.lineWidth = width;
    context.beginPath();
    context.moveTo(x1, y1);
    context.lineTo(x2, y2);
    context.stroke();
  }

  // The background, the grid (every grid step, or every metre when that is too dense) and the axes.
  paintGrid(gridStep) {
    const context = this.context;
    context.fillStyle = '#1d2126';
    context.fillRect(0, 0, this.canvas.width, this.canvas.height);
    const [left, top] = this.toFloor(0, 0);
    const [right, bottom] = this.toFloor(this.canvas.width, this.canvas.height);
    const step = this.scale * gridStep >= 6 ? gridStep : 1;
    for (let x = Math.ceil(left / step) * step; x <= right; x += step) {
      this.segment([x, bottom], [x, top], 1, Math.abs(x - Math.round(x)) < 1e-6 ? '#3e4650' : '#2a3037');
    }
    for (let y = Math.ceil(bottom / step) * step; y <= top; y += step) {
      this.segment([left, y], [right, y], 1, Math.abs(y - Math.round(y)) < 1e-6 ? '#3e4650' : '#2a3037');
    }
    this.segment([0, bottom], [0, top], 1, '#4f6e4f');
    this.segment([left, 0], [right, 0], 1, '#6e4f4f');
  }

  // The world's models, so that the building goes where it should; a name that would run
  // into one drawn already goes a line lower, or is left out when no line is free.
  // Returns the names drawn: {name, x, y, width, height} in canvas pixels.
  paintModels(poses) {
    const context = this.context;
    context.font = '11px system-ui, sans-serif';
    const labels = [];
    for (const [name, pose] of Object.entries(poses)) {
      const [x, y] = this.toCanvas(pose);
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
    return labels;
  }

  // Each wall's name at its middle, across it. Returns the names drawn, as paintModels does.
  paintWallNames(walls) {
    const context = this.context;
    const labels = [];
    context.font = 'bold 11px system-ui, sans-serif';
    walls.forEach((wall, index) => {
      const name = geometry.wallName(index);
      const [x, y] = this.toCanvas([(wall.start[0] + wall.end[0]) / 2, (wall.start[1] + wall.end[1]) / 2]);
      const width = context.measureText(name).width;
      const box = {name, x: x - width / 2, y: y - LABEL_HEIGHT / 2, width, height: LABEL_HEIGHT};
      context.fillStyle = 'rgba(29,33,38,0.8)';
      context.fillRect(box.x - 2, box.y, box.width + 4, box.height);
      context.fillStyle = '#ffd27f';
      context.fillText(name, box.x, box.y + LABEL_HEIGHT - 2);
      labels.push(box);
    });
    context.font = '11px system-ui, sans-serif';
    return labels;
  }
}

// The editor: its palette and inspector, the tool in hand and what the mouse is doing.
class BuildingEditor {
  constructor(studio) {
    this.studio = studio;
    this.plan = new PlanView(studio.view.canvas.parentElement);
    this.drawing = new Drawing(UNTITLED);
    this.tool = 'select';
    this.chain = null;            // {first, last}: the point the next click draws a wall to
    this.hover = null;            // where the next wall would end, placed
    this.selection = null;        // {kind: 'wall' | 'opening', index}
    this.labels = [];             // the models' names as drawn last
    this.wallLabels = [];         // the walls' names as drawn last
    this.pressed = null;          // the mouse press going on: {x, y, centre}
    this.buildPalette();
    this.shell = new EditorShell(studio, {
      title: 'Building Editor', kind: 'building', command: 'save_building', defaultFolder: 'building_folder',
      palette: this.palette, name: () => this.design.name,
      design: () => ({walls: this.design.walls.map((wall) => ({...wall})),
                      openings: this.design.openings.map((opening) => ({...opening}))}),
      savedAs: (reply) => this.savedAs(reply),
      reset: () => this.reset(),
      opened: () => this.opened(),
      closed: () => { this.plan.canvas.hidden = true; },
    });
    this.addEditMenu();
    this.listen();
    this.reset();
  }

  get design() {
    return this.drawing.design;
  }

  get settings() {
    return this.studio.settings.building;
  }

  // -- the palette -----------------------------------------------------------------------
  buildPalette() {
    this.palette = document.createElement('section');
    this.tools = new Map();
    const toolButton = (name, label, title) => {
      const button = makeButton(label, () => this.setTool(this.tool === name ? 'select' : name), title);
      button.setAttribute('aria-pressed', 'false');
      this.tools.set(name, button);
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
    nameInput.addEventListener('change', () => this.change(() => { this.design.name = nameInput.value; }));
    this.nameInput = nameInput;
    const nameForm = document.createElement('div');
    nameForm.className = 'form';
    nameForm.append(nameLabel, nameInput);
    this.hint = document.createElement('p');
    this.hint.className = 'hint';
    this.hint.setAttribute('role', 'status');
    this.hint.setAttribute('aria-label', 'Building Editor hint');
    this.inspector = document.createElement('div');
    this.inspector.className = 'inspector';
    this.inspector.setAttribute('role', 'group');
    this.palette.append(heading('Create Walls'), walls, heading('Add Features'), features, nameForm, this.hint,
                        this.inspector);
  }

  // Gazebo's editors have an Edit menu with Undo and Redo; the keys are the keymap's, in this mode.
  addEditMenu() {
    const studio = this.studio;
    studio.addAction('undo', () => this.undo(), {mode: 'building', keys: ['Ctrl+Z']});
    studio.addAction('redo', () => this.redo(), {mode: 'building', keys: ['Ctrl+Shift+Z']});
    studio.addAction('deleteSelected', () => this.removeSelected(), {mode: 'building', keys: ['Delete']});
    studio.addAction('endChain', () => this.setTool('select'), {mode: 'building', keys: ['Esc']});
    this.undoItem = this.shell.menus.add('Edit', {label: 'Undo', shortcut: 'Ctrl+Z', action: () => studio.run('undo')});
    this.redoItem = this.shell.menus.add('Edit', {label: 'Redo', shortcut: 'Ctrl+Shift+Z',
                                                  action: () => studio.run('redo')});
  }

  showUndo() {
    this.undoItem.setAttribute('aria-disabled', String(!this.drawing.history.canUndo));
    this.redoItem.setAttribute('aria-disabled', String(!this.drawing.history.canRedo));
  }

  // -- the design ------------------------------------------------------------------------
  reset() {
    this.drawing.reset(UNTITLED);
    this.nameInput.value = this.design.name;
    this.chain = null;
    this.selection = null;
    this.setTool('select');
  }

  // An edit of the design (change edits it in place): one step for Undo, and the page shows it.
  change(edit) {
    const result = this.drawing.edit(edit);
    this.shell.changed();
    this.showDesign();
    return result;
  }

  undo() {
    if (this.drawing.undo()) this.afterHistory();
  }

  redo() {
    if (this.drawing.redo()) this.afterHistory();
  }

  // The design is another one now: the chain drawn is ended, and a selection of what is gone too.
  afterHistory() {
    this.chain = null;
    const items = this.selection && (this.selection.kind === 'wall' ? this.design.walls : this.design.openings);
    if (items && !items[this.selection.index]) this.selection = null;
    this.nameInput.value = this.design.name;
    this.shell.changed();
    this.setTool(this.tool);
  }

  // The simulator saved the walls snapped as it snaps them: the design shows them so.
  savedAs(reply) {
    reply.walls.forEach((snapped, index) => Object.assign(this.design.walls[index], snapped));
    this.design.name = this.shell.saved.name;
    this.nameInput.value = this.design.name;
    this.draw();
  }

  showDesign() {
    this.showInspector();
    this.showUndo();
    this.draw();
  }

  setTool(name) {
    this.tool = name;
    if (name !== 'wall') this.chain = null;
    for (const [key, button] of this.tools) button.setAttribute('aria-pressed', String(key === name));
    this.hint.textContent = HINTS[name === 'wall' && !this.chain ? 'wallStart' : name];
    this.plan.canvas.classList.toggle('drawing', name !== 'select');
    this.showDesign();
  }

  // -- drawing -------------------------------------------------------------------------
  resize() {
    this.plan.resize();
    this.draw();
  }

  draw() {
    const plan = this.plan;
    if (plan.canvas.hidden || !this.settings) return;
    plan.paintGrid(this.settings.grid_step);
    this.labels = plan.paintModels(this.studio.poses);
    const chosen = (kind, index) => this.selection && this.selection.kind === kind && this.selection.index === index;
    this.design.walls.forEach((wall, index) => {
      plan.segment(wall.start, wall.end, Math.max(2, wall.thickness * plan.scale) + (chosen('wall', index) ? 4 : 0),
                   chosen('wall', index) ? '#f39c12' : rgb(wall.color));
    });
    this.design.openings.forEach((opening, index) => {
      const wall = this.design.walls[opening.wall];
      const [from, to] = geometry.openingEnds(wall, opening);
      plan.segment(from, to, Math.max(2, wall.thickness * plan.scale) + 2,
                   chosen('opening', index) ? '#f39c12' : (opening.kind === 'door' ? '#a0672d' : '#5dade2'));
    });
    this.wallLabels = plan.paintWallNames(this.design.walls);
    if (this.tool === 'wall' && this.hover) {
      const context = plan.context;
      if (this.chain) {
        plan.segment(this.chain.last, this.hover, Math.max(2, this.settings.wall.thickness * plan.scale),
                     'rgba(243,156,18,0.6)');
        // The wall's length as it is drawn, beside its middle, as Gazebo shows it.
        const [mx, my] = plan.toCanvas([(this.chain.last[0] + this.hover[0]) / 2,
                                        (this.chain.last[1] + this.hover[1]) / 2]);
        context.fillStyle = '#f39c12';
        context.fillText(geometry.drawnLength(this.chain, this.hover) + ' m', mx + 8, my - 8);
      }
      const [x, y] = plan.toCanvas(this.hover);
      context.strokeStyle = '#f39c12';
      context.lineWidth = 2;
      context.strokeRect(x - 4, y - 4, 8, 8);
    }
  }

  showDrawnLength() {
    const length = geometry.drawnLength(this.chain, this.hover);
    const base = this.hint.textContent.split(' \u2014 ')[0];
    this.hint.textContent = length === null ? base : base + ' \u2014 this wall: ' + length + ' m';
  }

  // -- the mouse -------------------------------------------------------------------------
  placed(point, free) {
    return geometry.placePoint(point, this.design.walls, this.settings, free);
  }

  clickAt(point, free = false) {
    if (this.tool === 'wall') return this.drawTo(this.placed(point, free));
    if (this.tool === 'door' || this.tool === 'window') return this.putOpening(this.tool, point);
    this.selection = geometry.pick(this.design, point, PICK_REACH);
    this.showDesign();
    return undefined;
  }

  drawTo(point) {
    const step = geometry.drawTo(this.chain, point, this.design.walls, this.settings);
    if (step.refused) return this.studio.notify(step.refused);
    this.chain = step.chain;
    if (step.wall) this.change((design) => { design.walls.push(step.wall); });
    this.setTool('wall');
    return undefined;
  }

  putOpening(kind, point) {
    const {opening, refused} = geometry.newOpening(this.design, kind, point, this.settings, PICK_REACH);
    if (refused) return this.studio.notify(refused);
    this.change((design) => { design.openings.push(opening); });
    this.selection = {kind: 'opening', index: this.design.openings.length - 1};
    this.setTool('select');
    return undefined;
  }

  listen() {
    const canvas = this.plan.canvas;
    canvas.addEventListener('pointerdown', (event) => {
      this.pressed = {x: event.clientX, y: event.clientY, centre: [...this.plan.centre]};
      canvas.setPointerCapture(event.pointerId);
    });
    canvas.addEventListener('pointermove', (event) => {
      const down = this.pressed;
      if (down && Math.hypot(event.clientX - down.x, event.clientY - down.y) > CLICK_SLOP) {
        this.plan.pan(down.centre, event.clientX - down.x, event.clientY - down.y);
      }
      this.hover = this.tool === 'wall' ? this.placed(this.plan.eventPoint(event), event.shiftKey) : null;
      if (this.tool === 'wall') this.showDrawnLength();
      this.draw();
    });
    canvas.addEventListener('pointerup', (event) => {
      const down = this.pressed;
      this.pressed = null;
      if (!down || event.button !== 0) return;
      if (Math.hypot(event.clientX - down.x, event.clientY - down.y) > CLICK_SLOP) return;
      this.clickAt(this.plan.eventPoint(event), event.shiftKey);
    });
    canvas.addEventListener('dblclick', () => {
      if (this.chain) this.setTool('select');
    });
    canvas.addEventListener('wheel', (event) => {
      event.preventDefault();
      this.plan.zoom(event);
      this.draw();
    }, {passive: false});
    new ResizeObserver(() => { if (!canvas.hidden) this.resize(); }).observe(this.plan.section);
    // Closing or reloading the tab would lose a design not saved: the browser asks first.
    window.addEventListener('beforeunload', (event) => {
      if (!this.shell.active || !this.shell.dirty) return;
      event.preventDefault();
      event.returnValue = '';
    });
    this.studio.on('poses', () => { if (this.shell.active) this.draw(); });
  }

  // -- the inspectors --------------------------------------------------------------------
  removeSelected() {
    const selection = this.selection;
    if (!selection) return;
    this.selection = null;
    this.change((design) => {
      if (selection.kind === 'wall') geometry.removeWall(design, selection.index);
      else design.openings.splice(selection.index, 1);
    });
  }

  // A field of the inspector, with its unit after it (every size here is in metres).
  numberField(label, read, write) {
    const [labelElement, input] = numberInput(this.studio, label, read, (value) => {
      if (value === null) return this.showInspector();
      return this.change(() => write(value));
    });
    const cell = document.createElement('span');
    cell.className = 'with-unit';
    const unit = document.createElement('span');
    unit.className = 'unit';
    unit.textContent = 'm';
    cell.append(input, unit);
    return [labelElement, cell];
  }

  showInspector() {
    const selection = this.selection;
    const inspector = this.inspector;
    const item = selection && (selection.kind === 'wall' ? this.design.walls : this.design.openings)[selection.index];
    inspector.hidden = !item;
    if (!item) return inspector.replaceChildren();
    const form = document.createElement('div');
    form.className = 'form';
    let title;
    const partName = document.createElement('output');
    partName.id = 'building-part-name';
    partName.value = selection.kind === 'wall' ? geometry.wallName(selection.index) : geometry.openingName(item);
    const partLabel = document.createElement('label');
    partLabel.textContent = 'Name';
    partLabel.htmlFor = partName.id;
    form.append(partLabel, partName);
    if (selection.kind === 'wall') {
      title = 'Wall Inspector';
      const point = (key, axis) => this.numberField((key === 'start' ? 'Start ' : 'End ') + 'XY'[axis],
                                                    () => item[key][axis], (value) => {
        item[key] = axis === 0 ? [value, item[key][1]] : [item[key][0], value];
      });
      const length = document.createElement('output');
      length.id = 'building-wall-length';
      length.value = geometry.round(geometry.wallLength(item)) + ' m';
      const lengthLabel = document.createElement('label');
      lengthLabel.textContent = 'Length';
      lengthLabel.htmlFor = length.id;
      const colour = colourInput(this.studio, 'Color', () => item.color, (values) => {
        this.change(() => { item.color = values; });
      });
      form.append(...point('start', 0), ...point('start', 1), ...point('end', 0), ...point('end', 1),
                  lengthLabel, length,
                  ...this.numberField('Height', () => item.height, (value) => { item.height = value; }),
                  ...this.numberField('Thickness', () => item.thickness, (value) => { item.thickness = value; }),
                  ...colour);
    } else {
      title = item.kind === 'door' ? 'Door Inspector' : 'Window Inspector';
      form.append(...this.numberField('Position', () => item.offset, (value) => { item.offset = value; }),
                  ...this.numberField('Width', () => item.width, (value) => { item.width = value; }),
                  ...this.numberField('Height', () => item.height, (value) => { item.height = value; }),
                  ...this.numberField('Elevation', () => item.elevation, (value) => { item.elevation = value; }));
    }
    inspector.setAttribute('aria-label', title);
    inspector.replaceChildren(heading(title), form, makeButton('Delete', () => this.removeSelected()));
    return undefined;
  }

  opened() {
    this.plan.canvas.setAttribute('aria-label', 'Building Editor drawing: the floor from above, '
                                  + this.settings.grid_step + ' m grid');
    this.plan.canvas.hidden = false;
    this.reset();
    this.resize();
    this.plan.canvas.focus();
  }

  // Open it, once the simulator has said what the editor draws with (its hello).
  open() {
    if (!this.settings) return this.studio.notify('Not connected to the simulator yet');
    return this.shell.open();
  }
}

export function mount(studio) {
  const editor = new BuildingEditor(studio);
  studio.addAction('buildingEditor', () => editor.open(), {keys: ['Ctrl+B']});
  studio.menus.add('Edit', {label: 'Building Editor', shortcut: 'Ctrl+B', action: () => studio.run('buildingEditor')});
  // For the tests, which draw with the mouse.
  studio.buildingEditor = {
    shell: editor.shell,
    get design() { return editor.design; },
    // The models' names as drawn last: {name, x, y, width, height} in canvas pixels.
    get labels() { return editor.labels; },
    // The walls' names as drawn last, in the same form.
    get wallLabels() { return editor.wallLabels; },
    // Where the floor point (x, y) is on the screen.
    screenPoint: (x, y) => editor.plan.screenPoint(x, y),
  };
}
