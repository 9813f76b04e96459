"""Stand-ins for the grader's unit tests: the rubric run's Session without a master or a
sandbox, a clock that stands still, and masters that hold given parameters."""
import os


class FixedClock:
    def now(self):
        return 1.5


def a_session(tmp_path, monkeypatch):
    """The rubric run's Session as grade makes it, without a master or a sandbox."""
    from chase_tools.grading.session import Session, SessionSpec
    monkeypatch.setattr(os, 'environ', dict(os.environ))      # the session sets ROS's variables
    spec = SessionSpec(overlay_env={}, overlay_root=str(tmp_path), run_scratch=str(tmp_path / 'run'),
                       out_dir=str(tmp_path / 'out'), robot_package='my_robot',
                       chaser_package='ball_chaser', isolate=False)
    session = Session(spec)
    session.clock = FixedClock()
    return session


class ParamMaster:
    """The parameters a submission's launch set, as the master gives them back."""

    def __init__(self, params):
        self.params = params

    def hasParam(self, name):  # noqa: N802 - the master's XML-RPC name
        return name in self.params

    def getParam(self, name):  # noqa: N802 - the master's XML-RPC name
        return self.params[name]


class DescriptionMaster(ParamMaster):
    def getParamNames(self):  # noqa: N802 - the master's XML-RPC name
        return sorted(self.params)
