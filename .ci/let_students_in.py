"""Let other users enter the folders above this Python and this checkout (CI, as root).

The graders' sandbox mounts the Python where it lies, so students' code needs no more. One
test runs a grader itself as the user ``nobody`` (a grader that is not root), and that user
must then be able to read this Python: pyenv's lives under /root, closed to other users on
these machines. This adds o+x (enter, not list) to each folder above the Python, the
virtual environment and the checkout that lacks it, and says which; ``.ci/run`` runs that
test after it, and the rest of the suite before it.
"""

import os
import sys
from pathlib import Path

if os.geteuid() != 0:
    sys.exit(0)
for path in {Path(sys.base_prefix), Path(sys.prefix), Path(__file__).resolve().parent.parent}:
    for folder in reversed(path.parents):
        mode = folder.stat().st_mode
        if not mode & 0o001:
            folder.chmod(mode | 0o001)
            print(f"{folder}: other users may now enter it (o+x)")
