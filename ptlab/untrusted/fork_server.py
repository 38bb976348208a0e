"""What the fork server of the students' processes does first: imported as its preload.

The grader starts one multiprocessing fork server and every student's process is a fork of
it (``ptlab.untrusted.submission``). Importing this module, the fork server

* makes itself non-dumpable (``ptlab.untrusted.processes.make_undumpable``): a student's
  process of the same user cannot ptrace it to fork processes of its choosing;
* imports every module of ptlab, the exercises' chapters included (whose checks may send
  objects of their own classes), so that the student's processes, which may not read
  ptlab's files (``ptlab.untrusted.confinement``), have all of it already.

Nothing else imports this module.
"""

from __future__ import annotations

import importlib
import pkgutil

import ptlab
from ptlab.untrusted.processes import make_undumpable

make_undumpable()
for _module in pkgutil.walk_packages(ptlab.__path__, "ptlab."):
    importlib.import_module(_module.name)
importlib.import_module("ptlab.exercises").all_chapters()
