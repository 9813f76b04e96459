// An editor's Undo and Redo: copies of its design as it was before each edit. The design
// is the page's until Save hands it to the simulator, so its history is the page's too.

// The most edits Undo goes back through.
const LIMIT = 200;

export class DesignHistory {
  constructor() {
    this.clear();
  }

  clear() {
    this.done = [];
    this.undone = [];
  }

  // Call before an edit, with the design as it is (copied here).
  record(state) {
    this.done.push(structuredClone(state));
    if (this.done.length > LIMIT) this.done.shift();
    this.undone = [];
  }

  // The design before the last edit (null if none); current is kept for Redo.
  undo(current) {
    if (!this.done.length) return null;
    this.undone.push(structuredClone(current));
    return this.done.pop();
  }

  redo(current) {
    if (!this.undone.length) return null;
    this.done.push(structuredClone(current));
    return this.undone.pop();
  }
}
