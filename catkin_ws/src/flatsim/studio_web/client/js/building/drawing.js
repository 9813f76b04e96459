// The Building Editor's design and its Undo and Redo, with no page in it. Every edit goes
// through edit(change): the design as it was is kept, so that Undo puts it back and Redo
// goes forward again; an edit that changed nothing is no step. A new edit forgets what
// could be redone, as in Gazebo's editors.

const copy = (value) => JSON.parse(JSON.stringify(value));

// How many steps Undo goes back at most.
export const UNDO_STEPS = 200;

export class History {
  constructor(limit = UNDO_STEPS) {
    this.limit = limit;
    this.past = [];
    this.future = [];
  }

  clear() {
    this.past = [];
    this.future = [];
  }

  // state: what there was before an edit.
  record(state) {
    this.past.push(copy(state));
    if (this.past.length > this.limit) this.past.shift();
    this.future = [];
  }

  get canUndo() {
    return this.past.length > 0;
  }

  get canRedo() {
    return this.future.length > 0;
  }

  // The state before current, or null; current is kept for Redo.
  undo(current) {
    if (!this.past.length) return null;
    this.future.push(copy(current));
    return this.past.pop();
  }

  // The state Undo left, or null; current is kept for Undo.
  redo(current) {
    if (!this.future.length) return null;
    this.past.push(copy(current));
    return this.future.pop();
  }
}

export function emptyDesign(name = 'Untitled') {
  return {name, walls: [], openings: []};
}

export class Drawing {
  constructor(name) {
    this.history = new History();
    this.design = emptyDesign(name);
  }

  reset(name) {
    this.design = emptyDesign(name);
    this.history.clear();
  }

  // Run change(design), which edits the design in place; one Undo step if it changed it.
  // Returns what change returned.
  edit(change) {
    const before = copy(this.design);
    const result = change(this.design);
    if (JSON.stringify(before) !== JSON.stringify(this.design)) this.history.record(before);
    return result;
  }

  // Whether there was a step to undo (or redo).
  undo() {
    const previous = this.history.undo(this.design);
    if (previous) this.design = previous;
    return previous !== null;
  }

  redo() {
    const next = this.history.redo(this.design);
    if (next) this.design = next;
    return next !== null;
  }
}
