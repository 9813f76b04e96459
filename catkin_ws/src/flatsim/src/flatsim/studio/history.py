"""Undo and Redo in the world, as Gazebo's Edit menu has them: Insert, Paste, Delete, Move and
Scale.

The history lives here, on the server, beside the simulator, not in a page: Gazebo keeps its
user commands in the server too (gzserver's UserCmdManager), so that every window sees one
history. Two tabs are two windows on one world: an insert made in one is undone from the
other, and each page only asks for 'undo' or 'redo' and redraws what the simulator streams.

Each Edit touches one model, by name, and is undone and redone through the simulator's
real state (the WorldAccess): an Insert or Paste is undone by deleting the model and redone
by placing the kept copy again at the pose it was given; a Delete is undone by placing the
kept model again, with its SDF, origin and pose; a Move is undone by setting the pose it had
before and redone by setting the pose it was given; a Scale (the simulator places the model
anew with its new sizes, under its name) is undone by deleting the scaled model and placing the
kept one from before again, and redone the other way round. A drag is one Move: the set_poses a page
sends while it holds the model's lease join the Move its first one opened, until the page
releases the model.

Changes from outside the studio (a ROS node, /gazebo/spawn_model, /gazebo/delete_model):
  - a model that moved (a robot pushed the ball, /gazebo/set_model_state) keeps its edits:
    Undo of a Move sets the pose recorded before it anyway, as Gazebo's Undo puts the world
    back as it was before the command;
  - a model that was deleted, or a model under that name that is not the one the history
    left there (deleted and spawned again, or spawned where an Undo had taken one out), takes
    its edits out of the history: undoing them would delete, move or re-create something
    the user never edited here. notice() finds these from the models' identities (the
    snapshot's models_key); the hub calls it whenever it reads the world.
No ROS here.
"""
from dataclasses import dataclass

from flatsim.pose import Pose
from flatsim.studio.world import KeptModel, Outcome

# The most edits Undo goes back through (a kept model holds its whole description).
MAX_EDITS = 100
INSERT, PASTE, DELETE, MOVE, SCALE = 'Insert', 'Paste', 'Delete', 'Move', 'Scale'


@dataclass
class Edit:
    """One user edit of one model."""
    action: str                    # INSERT | PASTE | DELETE | MOVE | SCALE
    model: str
    kept: KeptModel = None         # Insert, Paste, Scale: the model as placed; Delete: as it was
    replaced: KeptModel = None     # Scale: the model as it was before
    before: Pose = None            # Move: where it was, and where it was put
    after: Pose = None
    mover: object = None           # Move: the session still moving it (its drag goes on)

    @property
    def label(self):
        return '%s %s' % (self.action, self.model)

    def exists_after(self, undone):
        """Whether the model is in the world once this edit is done (or undone)."""
        if self.action in (MOVE, SCALE):
            return True
        return self.action == DELETE if undone else self.action != DELETE

    def undo(self, world) -> Outcome:
        if self.action == MOVE:
            return world.set_model_pose(self.model, self.before)
        if self.action == SCALE:
            return _swap(world, self.replaced, self.kept)
        if self.action == DELETE:
            return world.restore_model(self.kept)
        return world.delete_model(self.model)

    def redo(self, world) -> Outcome:
        if self.action == MOVE:
            return world.set_model_pose(self.model, self.after)
        if self.action == SCALE:
            return _swap(world, self.kept, self.replaced)
        if self.action == DELETE:
            return world.delete_model(self.model)
        return world.restore_model(self.kept)


def _swap(world, wanted, present):
    """The model as it is (present) makes way for the one kept as wanted, under its name and at
    wanted's pose; if wanted cannot be placed, present is put back, so that nothing is lost."""
    deleted = world.delete_model(present.name)
    if not deleted.ok:
        return deleted
    placed = world.restore_model(wanted)
    if not placed.ok:
        world.restore_model(present)
    return placed


class History:
    """The edits done (Undo takes the last) and undone (Redo takes the last).

    expected: model -> the identity the history left it with (None: the history took it out);
    a model whose identity is another now was changed from outside (see notice()).
    """

    def __init__(self, limit=MAX_EDITS):
        self.limit = limit
        self.done = []
        self.undone = []
        self.expected = {}

    # -- what the pages see ---------------------------------------------------------------
    def labels(self):
        """{'undo': [labels, next first], 'redo': [...]}, for the Edit menu."""
        return {'undo': [edit.label for edit in reversed(self.done)],
                'redo': [edit.label for edit in reversed(self.undone)]}

    # -- recording -------------------------------------------------------------------------
    def record(self, edit, identity):
        """A new edit, done; identity: its model's identity now (None if it is gone). Redo
        forgets what was undone, as in every editor."""
        self.close_move()
        self.done.append(edit)
        del self.done[:-self.limit]
        self.undone.clear()
        self.expected[edit.model] = identity
        self._forget_unused()

    def moving(self, session, model):
        """The Move that session's drag of model has open, or None."""
        top = self.done[-1] if self.done else None
        if top is not None and top.action == MOVE and top.mover is session and top.model == model:
            return top
        return None

    def moved(self, session, model, before, after, identity):
        """session set model's pose to after: the Move its drag has open goes on, or a new
        Move from before (the pose before this set_pose) begins. True if a Move began."""
        move = self.moving(session, model)
        if move is not None:
            move.after = after
            return False
        self.record(Edit(MOVE, model, before=before, after=after, mover=session), identity)
        return True

    def close_move(self, session=None, model=None):
        """The open Move (of session, of model, if given) is finished: the next set_pose
        begins another."""
        top = self.done[-1] if self.done else None
        if top is not None and top.mover is not None and session in (None, top.mover) \
                and model in (None, top.model):
            top.mover = None

    # -- undo and redo ---------------------------------------------------------------------
    def next_undo(self):
        return self.done[-1] if self.done else None

    def next_redo(self):
        return self.undone[-1] if self.undone else None

    def undo(self, world, identity_of):
        """Undo the last edit through world; identity_of(model) reads its identity after.
        Returns (edit, Outcome); a refused undo stays in the history."""
        return self._step(self.done, self.undone, world, identity_of, undo=True)

    def redo(self, world, identity_of):
        return self._step(self.undone, self.done, world, identity_of, undo=False)

    def _step(self, source, target, world, identity_of, undo):
        if not source:
            return None, Outcome(False, 'there is nothing to %s' % ('undo' if undo else 'redo'))
        edit = source[-1]
        edit.mover = None
        outcome = edit.undo(world) if undo else edit.redo(world)
        if not outcome.ok:
            return edit, outcome
        source.pop()
        target.append(edit)
        self.expected[edit.model] = identity_of(edit.model) if edit.exists_after(undo) else None
        return edit, outcome

    # -- changes from outside --------------------------------------------------------------
    def notice(self, identities):
        """identities: model -> identity, of every model in the world now. The edits of each
        model that is not as the history left it are dropped; returns those models' names."""
        changed = sorted(model for model, identity in self.expected.items()
                         if identities.get(model) != identity)
        for model in changed:
            self.done = [edit for edit in self.done if edit.model != model]
            self.undone = [edit for edit in self.undone if edit.model != model]
            del self.expected[model]
        return changed

    def _forget_unused(self):
        """Models no edit names any more need no watching."""
        named = {edit.model for edit in self.done} | {edit.model for edit in self.undone}
        for model in [model for model in self.expected if model not in named]:
            del self.expected[model]
