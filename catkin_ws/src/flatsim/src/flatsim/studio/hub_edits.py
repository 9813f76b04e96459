"""Who edits what in the studio, and Edit > Undo and Redo: the hub's edit leases (one page at
a time per model) and its history of edits (flatsim.studio.history). No ROS here."""
from flatsim.errors import FlatsimError
from flatsim.studio.protocol import CommandError

# How long an edit lease lasts without a new edit from its holder.
LEASE_SECONDS = 2.0


class HubEdits:
    """Hub's leases and history; Hub (flatsim.studio.hub) sets up the state they use."""

    # -- edit leases -----------------------------------------------------------------
    def take_lease(self, session, model):
        """Make session the one editing model for LEASE_SECONDS, or refuse clearly."""
        now = self.clock()
        held = self.leases.get(model)
        if held is not None and held[0] is not session and held[1] > now:
            raise CommandError('%s is being edited in %s; try again when it is done there'
                               % (model, held[0].label))
        self.leases[model] = (session, now + LEASE_SECONDS)
        if held is None or held[0] is not session:
            self.broadcast(self._leases_message())

    def check_free(self, session, model):
        """Refuse if another page is editing model (without taking it: an Undo is one step)."""
        held = self.leases.get(model)
        if held is not None and held[0] is not session and held[1] > self.clock():
            raise CommandError('%s is being edited in %s; try again when it is done there'
                               % (model, held[0].label))

    def release_lease(self, session, model):
        self.history.close_move(session, model)
        held = self.leases.get(model)
        if held is not None and held[0] is session:
            del self.leases[model]
            self.broadcast(self._leases_message())

    def _expire_leases(self, now):
        expired = [model for model, (_, expiry) in self.leases.items() if expiry <= now]
        for model in expired:
            self.history.close_move(self.leases[model][0], model)
            del self.leases[model]
        if expired:
            self.broadcast(self._leases_message())

    def _leases_message(self):
        return {'type': 'leases',
                'leases': {model: holder.id for model, (holder, _) in self.leases.items()}}

    # -- undo and redo -----------------------------------------------------------------
    def snapshot(self):
        """The world now (WorldAccess.snapshot); the history first drops what was changed
        from outside. Every read of the world goes through here, so that none is missed."""
        snapshot = self.world.snapshot()
        if snapshot.models_key != self.noticed_key:
            self._notice(dict(snapshot.models_key))
            self.noticed_key = snapshot.models_key
        return snapshot

    def _notice(self, identities):
        dropped = self.history.notice(identities)
        if dropped:
            self.log.info('studio: %s changed outside the studio; Undo leaves %s',
                          ', '.join(dropped), 'it' if len(dropped) == 1 else 'them')
            self.broadcast(self._history_message(dropped))

    def _identities(self):
        """model -> identity, read now (without noticing: the history's own change comes first)."""
        return dict(self.world.snapshot().models_key)

    def record(self, edit):
        """An edit the studio just made joins the history, and every page is told."""
        identities = self._identities()
        self.history.record(edit, identities.get(edit.model))
        self._notice(identities)
        self.broadcast(self._history_message())

    def keep(self, model):
        """The model kept for Undo, or None (logged) if it cannot be."""
        try:
            return self.world.keep_model(model)
        except FlatsimError as error:
            self.log.warning('studio: %s cannot be kept for Undo: %s', model, error)
            return None

    def undo_or_redo(self, session, undo):
        self.snapshot()
        edit = self.history.next_undo() if undo else self.history.next_redo()
        if edit is None:
            raise CommandError('there is nothing to %s' % ('undo' if undo else 'redo'))
        self.check_free(session, edit.model)
        step = self.history.undo if undo else self.history.redo
        edit, outcome = step(self.world, lambda model: self._identities().get(model))
        if not outcome.ok:
            raise CommandError('cannot %s %s: %s' % ('undo' if undo else 'redo', edit.label,
                                                     outcome.message))
        if edit.exists_after(undo):
            self.model_names.add(edit.model)
        else:
            self.model_names.discard(edit.model)
        self.log.info('studio: %s: %s %s', session.label, 'Undo' if undo else 'Redo', edit.label)
        self.broadcast(self._history_message())
        return {'edit': edit.label, 'message': '%s %s' % ('Undo' if undo else 'Redo', edit.label)}

    def _history_message(self, dropped=()):
        return dict(self.history.labels(), type='history', dropped=list(dropped))

    def check_model(self, name):
        if name not in self.model_names:
            raise CommandError('there is no model named %r in the world (models: %s)'
                               % (name, ', '.join(sorted(self.model_names)) or 'none'))

