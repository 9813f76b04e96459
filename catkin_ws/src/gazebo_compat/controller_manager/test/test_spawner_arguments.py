"""The spawner's controller arguments: names, YAML files, and files it cannot use."""
import pytest
import rosparam
import rospy

from controller_manager.spawner import controller_names, parse_args


@pytest.fixture
def server(monkeypatch):
    """The parameters the spawner sets and the errors it logs, without a master."""
    seen = {'params': [], 'errors': []}
    monkeypatch.setattr(rosparam, 'set_param_raw', lambda name, value: seen['params'].append((name, value)))
    monkeypatch.setattr(rospy, 'logerr', lambda text, *args: seen['errors'].append(text % args))
    return seen


def test_a_controllers_file_is_loaded_and_gives_its_controllers(server, tmp_path):
    path = tmp_path / 'controllers.yaml'
    path.write_text('joint_state_controller:\n  type: joint_state_controller/JointStateController\n'
                    '  publish_rate: 50\narm_controller: {type: effort_controllers/JointEffortController}\n')
    assert controller_names([str(path), 'other_controller']) == [
        'joint_state_controller', 'arm_controller', 'other_controller']
    assert server['params'] == [('', {
        'joint_state_controller': {'type': 'joint_state_controller/JointStateController', 'publish_rate': 50},
        'arm_controller': {'type': 'effort_controllers/JointEffortController'}})]
    assert server['errors'] == []


@pytest.mark.parametrize('text, reason', [
    ('arm_controller: {type: [unclosed\n', 'cannot load %s: while parsing'),
    ('- just\n- a list\n', '%s holds no controllers'),
    ('', '%s holds no controllers'),
])
def test_a_file_it_cannot_use_is_named_and_the_others_go_on(server, tmp_path, text, reason):
    path = tmp_path / 'controllers.yaml'
    path.write_text(text)
    assert controller_names([str(path), 'joint_state_controller']) == ['joint_state_controller']
    assert server['params'] == []
    assert len(server['errors']) == 1
    assert server['errors'][0].startswith('Controller Spawner: ' + reason % path)


def test_a_missing_file_is_named_and_tried_as_a_controller_name(server):
    assert controller_names(['/nonexistent/controllers.yaml']) == ['/nonexistent/controllers.yaml']
    assert server['errors'] == ['Controller Spawner: /nonexistent/controllers.yaml looks like a YAML file '
                                'of controllers, but there is no such file; trying it as a controller name']


def test_arguments_are_the_real_spawners():
    args = parse_args(['--stopped', '--namespace', '/simple_arm', '--timeout', '5', 'a', 'b'])
    assert (args.stopped, args.namespace, args.timeout, args.controllers) == (True, '/simple_arm', 5.0, ['a', 'b'])
    with pytest.raises(SystemExit):
        parse_args([])
