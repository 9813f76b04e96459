"""The checkout meets its linter's rules (ruff.toml): pycodestyle, pyflakes, pep8-naming, and
a reason on every blind except."""
import os
import shutil
import subprocess

TOP = os.path.join(os.path.dirname(os.path.abspath(__file__)), os.pardir)


def test_the_code_meets_ruff_s_rules():
    ruff = shutil.which('ruff')
    assert ruff, 'ruff is not installed: ./setup.sh installs it from requirements.txt'
    found = subprocess.run([ruff, 'check', '--no-cache', '--output-format', 'concise', '.'], cwd=TOP,
                           capture_output=True, text=True, timeout=300)
    assert found.returncode == 0, found.stdout + found.stderr
