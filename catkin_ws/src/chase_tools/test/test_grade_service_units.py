"""A submission's own service type, read from its .srv text (grading/service_type.py): parsed
into request and response, checked against the course's request, and built into classes whose
md5 agrees with genpy's. No master."""
import io
import os

import pytest

from chase_tools.grading import course_service, service_type

COURSE_SRV = 'float64 linear_x\nfloat64 angular_z\n---\nstring msg_feedback\n'
VELOCITIES_SRV = ('# what drive_bot was asked\nfloat64 linear_x   # m/s\nfloat64 angular_z\n---\n'
                  'float64 linear_x_out\nfloat64 angular_z_out\n')
TYPE = 'ball_chaser/DriveToTarget'


def serialized(message):
    buffer = io.BytesIO()
    message.serialize(buffer)
    return buffer.getvalue()


def test_the_course_srv_gives_the_course_md5_and_classes_that_agree_with_genpy_s():
    course = course_service.course_drive_to_target()
    definition = service_type.parse_srv(COURSE_SRV, TYPE)
    assert definition.request == (('float64', 'linear_x'), ('float64', 'angular_z'))
    assert definition.response == (('string', 'msg_feedback'),)
    assert definition.md5 == course._md5sum == course_service.COURSE_MD5
    built = service_type.service_class(definition)
    assert (built._type, built._md5sum) == (course._type, course._md5sum)
    assert built._request_class._md5sum == course._request_class._md5sum
    assert built._response_class._md5sum == course._response_class._md5sum
    assert serialized(built._request_class(0.25, -0.35)) == serialized(course._request_class(0.25, -0.35))
    assert service_type.has_course_request(definition) and service_type.response_is_course(definition)


def test_a_srv_of_another_response_keeps_the_course_request_and_gets_its_own_md5():
    course = course_service.course_drive_to_target()
    definition = service_type.parse_srv(VELOCITIES_SRV, TYPE, 'ball_chaser/srv/DriveToTarget.srv')
    assert definition.request == service_type.COURSE_REQUEST
    assert definition.response == (('float64', 'linear_x_out'), ('float64', 'angular_z_out'))
    assert service_type.has_course_request(definition)
    assert not service_type.response_is_course(definition)
    assert definition.md5 != course._md5sum
    # Comments are not part of a type: the file without them has the same md5.
    bare = service_type.parse_srv('float64 linear_x\nfloat64 angular_z\n---\n'
                                  'float64 linear_x_out\nfloat64 angular_z_out\n', TYPE)
    assert bare.md5 == definition.md5
    built = service_type.service_class(definition)
    assert built._md5sum == definition.md5
    # The same request on the wire as the course's, and its own response read back.
    assert serialized(built._request_class(0.4, 0.1)) == serialized(course._request_class(0.4, 0.1))
    answer = built._response_class().deserialize(serialized(built._response_class(0.25, -0.35)))
    assert (answer.linear_x_out, answer.angular_z_out) == (0.25, -0.35)
    assert service_type.answer_text(answer) == 'linear_x_out 0.25, angular_z_out -0.35'
    assert service_type.answer_text(course._response_class('moving')) == 'moving'
    # What an extra world is handed gives the same definition back.
    again = service_type.parse_srv(service_type.definition_text(definition), TYPE)
    assert (again.request, again.response, again.md5) == (definition.request, definition.response,
                                                          definition.md5)


@pytest.mark.parametrize('request_text', ['float64 speed\nfloat64 turn\n',
                                          'float32 linear_x\nfloat32 angular_z\n',
                                          'float64 angular_z\nfloat64 linear_x\n',
                                          'float64 linear_x\n',
                                          'float64 linear_x\nfloat64 angular_z\nfloat64 duration\n'])
def test_a_request_other_than_the_course_s_is_told_apart(request_text):
    definition = service_type.parse_srv(request_text + '---\nstring msg_feedback\n', TYPE)
    assert not service_type.has_course_request(definition)


def test_the_fields_are_named_as_the_srv_declares_them():
    definition = service_type.parse_srv('float64 speed\nfloat64 turn\n---\nbool success\n', TYPE)
    assert service_type.fields_text(definition.request) == 'float64 speed, float64 turn'
    assert service_type.fields_text(definition.response) == 'bool success'
    assert service_type.fields_text(()) == 'nothing'


@pytest.mark.parametrize('text, why', [
    ('float64 linear_x\nfloat64 angular_z\n', 'has no --- between request and response'),
    ('float64 linear_x\nfloat64 angular_z\n---\nHeader header\n',
     'its response has the field std_msgs/Header header, of a message type the grader does not read'),
    ('float64 linear_x\nfloat64 angular_z\n---\ngeometry_msgs/Twist twist\n',
     'its response has the field geometry_msgs/Twist twist'),
    ('float64 linear_x\nfloat64 angular_z\n---\nstring NOTE="x"\nstring msg_feedback\n',
     'its response has the constant string NOTE, which the grader does not read'),
    ('float64 linear_x linear_y\n---\n', 'is not a service definition'),
])
def test_a_srv_the_grader_cannot_build_says_why(text, why):
    with pytest.raises(service_type.ServiceTypeError) as raised:
        service_type.parse_srv(text, TYPE)
    assert why in str(raised.value)


@pytest.mark.parametrize('type_name', ['DriveToTarget', 'ball_chaser/Drive"; import os', '../x/y', None])
def test_a_type_name_that_is_not_package_slash_name_is_refused(type_name):
    with pytest.raises(service_type.ServiceTypeError, match='is not a package/Name'):
        service_type.parse_srv(COURSE_SRV, type_name)


def test_comments_of_the_srv_never_reach_the_generated_code():
    text = ('# """ + __import__("os").getpid() + """\nfloat64 linear_x\nfloat64 angular_z\n---\n'
            'int32 OK=1\nfloat64 linear_x_out # """ x\n')
    definition = service_type.parse_srv(text, TYPE)
    assert '#' not in definition.request_text + definition.response_text
    assert definition.response_text == 'int32 OK=1\nfloat64 linear_x_out\n'
    built = service_type.service_class(definition)
    assert '__import__' not in built._request_class._full_text
    assert built._response_class.OK == 1


def write_srv(workspace, text, name='DriveToTarget.srv'):
    folder = os.path.join(str(workspace), 'src', 'ball_chaser', 'srv')
    os.makedirs(folder, exist_ok=True)
    path = os.path.join(folder, name)
    with open(path, 'w') as stream:
        stream.write(text)
    return path


def test_the_definition_is_read_from_the_chaser_s_srv_folder_by_the_served_type_name(tmp_path):
    write_srv(tmp_path, VELOCITIES_SRV)
    served = service_type.parse_srv(VELOCITIES_SRV, TYPE).md5
    definition = service_type.read_definition(str(tmp_path), 'ball_chaser', TYPE, served)
    assert definition.source == 'ball_chaser/srv/DriveToTarget.srv'
    assert definition.response == (('float64', 'linear_x_out'), ('float64', 'angular_z_out'))


def test_a_srv_that_is_not_what_is_served_is_refused_with_both_md5s(tmp_path):
    write_srv(tmp_path, VELOCITIES_SRV)
    mine = service_type.parse_srv(VELOCITIES_SRV, TYPE).md5
    with pytest.raises(service_type.ServiceTypeError) as raised:
        service_type.read_definition(str(tmp_path), 'ball_chaser', TYPE, course_service.COURSE_MD5)
    assert str(raised.value) == ('ball_chaser/srv/DriveToTarget.srv gives md5 %s, not the md5 %s it is '
                                 'served with' % (mine, course_service.COURSE_MD5))


def test_a_missing_or_linked_srv_is_not_read(tmp_path):
    with pytest.raises(service_type.ServiceTypeError, match='ball_chaser/srv/Drive.srv could not be read'):
        service_type.read_definition(str(tmp_path), 'ball_chaser', 'ball_chaser/Drive')
    elsewhere = tmp_path / 'elsewhere.srv'
    elsewhere.write_text(COURSE_SRV)
    os.makedirs(tmp_path / 'src' / 'ball_chaser' / 'srv', exist_ok=True)
    os.symlink(str(elsewhere), str(tmp_path / 'src' / 'ball_chaser' / 'srv' / 'DriveToTarget.srv'))
    with pytest.raises(service_type.ServiceTypeError, match='could not be read'):
        service_type.read_definition(str(tmp_path), 'ball_chaser', TYPE)
