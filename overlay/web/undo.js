// Undo and redo of the labelling page's edits, without the DOM (tested with node --test). Each
// state is a labels document (plain JSON data), kept as its own copy.

const copy = (value) => JSON.parse(JSON.stringify(value));

export class UndoStack {
  /** Starts at `initial`; at most `limit` states are kept (the oldest go first). */
  constructor(initial, limit = 500) {
    this.states = [copy(initial)];
    this.index = 0;
    this.limit = Math.max(2, limit);
  }

  /** The current state (a copy: editing it changes nothing here). */
  get current() {
    return copy(this.states[this.index]);
  }

  get canUndo() {
    return this.index > 0;
  }

  get canRedo() {
    return this.index < this.states.length - 1;
  }

  /** Records an edit: `state` becomes current; what could be redone is dropped. An edit that
   *  changes nothing is not recorded (returns false). */
  push(state) {
    if (JSON.stringify(state) === JSON.stringify(this.states[this.index])) return false;
    this.states.splice(this.index + 1);
    this.states.push(copy(state));
    if (this.states.length > this.limit) this.states.shift();
    this.index = this.states.length - 1;
    return true;
  }

  /** Goes one edit back; returns the new current state, or null when there is none. */
  undo() {
    if (!this.canUndo) return null;
    this.index -= 1;
    return this.current;
  }

  /** Goes one edit forward again; returns the new current state, or null when there is none. */
  redo() {
    if (!this.canRedo) return null;
    this.index += 1;
    return this.current;
  }

  /** Replaces the current state without recording an edit (e.g. the server's normalised copy). */
  replaceCurrent(state) {
    this.states[this.index] = copy(state);
  }
}
