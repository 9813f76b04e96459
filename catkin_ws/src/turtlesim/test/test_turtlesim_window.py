"""The TurtleSim window: refused without a display, and under a virtual
display it shows the pictures it is handed and closes when told."""
import os
import shutil
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from turtlesim.window import CanvasWindow, WindowUnavailable, encode_ppm


def test_ppm_header_gives_columns_then_rows():
    frame = np.zeros((2, 3, 3), dtype=np.uint8)
    frame[1, 2] = (1, 2, 3)
    data = encode_ppm(frame)
    assert data.startswith(b'P6 3 2 255\n')
    assert data.endswith(b'\x01\x02\x03')


def test_no_display_no_window(monkeypatch):
    monkeypatch.delenv('DISPLAY', raising=False)
    with pytest.raises(WindowUnavailable, match='DISPLAY is not set'):
        CanvasWindow('TurtleSim', lambda: None, lambda: True, lambda: None)


@pytest.mark.skipif(shutil.which('xvfb-run') is None, reason='needs xvfb-run')
def test_window_shows_the_picture_under_a_virtual_display():
    script = textwrap.dedent('''
        import numpy as np
        from turtlesim.window import CanvasWindow
        frame = np.full((500, 500, 3), (69, 86, 255), dtype=np.uint8)
        frame[100, 200] = (255, 0, 0)
        pictures = [frame]
        refreshes = []
        def next_picture():
            refreshes.append(1)
            return pictures.pop() if pictures else None
        window = CanvasWindow('TurtleSim', next_picture, lambda: len(refreshes) < 3, lambda: None)
        window.root.update()
        print(window.root.title(), window.photo.width(), window.photo.height(),
              window.photo.get(200, 100), window.photo.get(0, 0))
        window.run()
        print('closed')
    ''')
    result = subprocess.run(['xvfb-run', '-a', sys.executable, '-c', script], capture_output=True, text=True,
                            timeout=60, env=dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path)))
    assert result.returncode == 0, result.stderr
    assert result.stdout.split('\n')[:2] == ['TurtleSim 500 500 (255, 0, 0) (69, 86, 255)', 'closed']
