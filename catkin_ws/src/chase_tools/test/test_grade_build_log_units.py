"""What a submission's build log tells (grading/overlay.py): the headers its C++ code lacks
and the make goal that failed. No master."""

from chase_tools.grading import overlay


# -- build logs ----------------------------------------------------------------------------

GCC_NO_NOTE = """\
/ws/src/ball_chaser/src/process_image.cpp: In function 'void process_image_callback(sensor_msgs::Image)':
/ws/src/ball_chaser/src/process_image.cpp:31:24: error: 'accumulate' is not a member of 'std'
   31 |     long column = std::accumulate(columns.begin(), columns.end(), 0L);
make[2]: *** [ball_chaser/CMakeFiles/process_image.dir/build.make:76: process_image.cpp.o] Error 1
"""
GCC_WITH_NOTE = """\
a.cpp:3:8: error: 'string' in namespace 'std' does not name a type
a.cpp:1:1: note: 'std::string' is defined in header '<string>'; did you forget to '#include <string>'?
b.cpp:9:5: error: 'numeric_limits' was not declared in this scope
"""


def test_missing_headers_come_from_the_compilers_notes_and_the_known_names():
    assert overlay.missing_headers(GCC_NO_NOTE) == {'numeric': ['accumulate']}
    assert overlay.missing_headers(GCC_WITH_NOTE) == {'limits': ['numeric_limits'],
                                                      'string': ['string']}


def test_an_unknown_name_is_not_taken_for_a_missing_header():
    assert overlay.missing_headers("x.cpp:1:1: error: 'drive_robt' was not declared in this scope") == {}


MESSAGES_FAILED = """\
make[3]: *** [ball_chaser/CMakeFiles/boom.dir/build.make:70: ball_chaser/CMakeFiles/boom] Error 1
make[2]: *** [CMakeFiles/Makefile2:716: ball_chaser/CMakeFiles/boom.dir/all] Error 2
make[1]: *** [CMakeFiles/Makefile2:511: ball_chaser/CMakeFiles/ball_chaser_generate_messages.dir/rule] Error 2
make: *** [Makefile:361: ball_chaser_generate_messages] Error 2
"""


def test_the_goal_that_failed_is_the_top_level_makes():
    assert overlay.failed_goal(MESSAGES_FAILED) == 'ball_chaser_generate_messages'
    assert overlay.failed_goal(GCC_NO_NOTE) is None


def test_error_lines_keep_the_first_of_each():
    lines = overlay.error_lines(GCC_NO_NOTE + GCC_NO_NOTE)
    assert lines[0].endswith("error: 'accumulate' is not a member of 'std'")
    assert len(lines) == 2
