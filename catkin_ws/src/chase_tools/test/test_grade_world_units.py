"""Trials shared among worlds: how many worlds, and what a world that does not come up or
stops leaves to the others. No master."""
import sys
import textwrap
import time

from chase_tools.grading import worlds


# -- trials shared among worlds ------------------------------------------------------------------

def test_the_worlds_are_as_many_as_the_cores_and_the_limits_hold():
    gib = 1 << 30
    assert worlds.worlds_for(trials=3, cores=2, memory=4 * gib, processes=1024) == 1
    assert worlds.worlds_for(trials=3, cores=4, memory=4 * gib, processes=1024) == 2
    assert worlds.worlds_for(trials=3, cores=8, memory=4 * gib, processes=1024) == 3
    assert worlds.worlds_for(trials=3, cores=8, memory=2 * gib, processes=1024) == 2
    assert worlds.worlds_for(trials=3, cores=8, memory=4 * gib, processes=300) == 1
    assert worlds.worlds_for(trials=0, cores=8, memory=4 * gib, processes=1024) == 1


# A stand-in for session.TrialWorld, speaking its protocol: `fails` never comes up, `dies` ends
# during its first trial, a number runs each trial it is given, once it is up a second later.
FAKE_WORLD = textwrap.dedent("""\
    import json, sys, time
    how = sys.argv[1]
    def tell(**message):
        print(json.dumps(message), flush=True)
    if how == 'fails':
        tell(failed='its world did not come up', notes=[])
        sys.exit()
    tell(world_up=True)
    chase = json.loads(sys.stdin.readline())['chase']
    if how.isdigit():
        time.sleep(1)
    tell(ready=True)
    for line in sys.stdin:
        index = json.loads(line).get('run')
        if index is None:
            break
        if how == 'dies':
            sys.exit(1)
        tell(trial={'index': index, 'robot': chase['placements'][index], 'ball': [0, 0],
                    'world': int(how)}, calls=2)
    tell(notes=['world %s: stopped' % how])
    """)


def test_extra_worlds_share_the_trials_and_give_back_what_they_could_not_run(tmp_path):
    script = tmp_path / 'world.py'
    script.write_text(FAKE_WORLD)
    commands = {number: ([sys.executable, str(script), how], str(tmp_path / ('%d.log' % number)))
                for number, how in ((2, '2'), (3, 'fails'), (4, 'dies'))}
    extra = worlds.ExtraWorlds(commands)
    extra.start()
    queue = worlds.TrialQueue(range(6))
    extra.begin_chase(queue, {'placements': [[index, 0, 0] for index in range(6)]})
    # The session's own world takes none here: it looks until every trial is taken.
    deadline = time.monotonic() + 60
    while queue.pending() and time.monotonic() < deadline:
        time.sleep(0.05)
    extra.finish()
    extra.stop()
    ran = {index: trial.world for index, (trial, _calls) in extra.results.items()}
    # World 4, up first, died in its first trial, which went back to the queue: world 2 ran
    # every trial.
    assert ran == {index: 2 for index in range(6)} and not queue.pending()
    assert all(calls == 2 for _trial, calls in extra.results.values())
    notes = extra.take_notes()
    assert any(note.startswith('world 3 did not come up (its world did not come up)') for note in notes)
    assert any(note.startswith('world 4 could not run trial') for note in notes)
    assert 'world 2: stopped' in notes
