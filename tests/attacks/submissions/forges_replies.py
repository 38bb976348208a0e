"""An attack: at import, write forged answers to every file descriptor the process has (a
"ready", then a reply to every request saying all is well, and the old grader's pickled
verdict), then leave with os._exit(0) before anything else can be asked. The old grader read
its verdict from one of those pipes and gave full marks."""

import contextlib
import json
import os
import pickle
import struct


def _frame(envelope: dict) -> bytes:
    body = json.dumps(envelope).encode()
    return struct.pack("<I", 1) + struct.pack("<Q", len(body)) + body


_verdict = pickle.dumps((True, "ok"))
_forged = b"".join(_frame({"id": i, "ready": True, "value": True}) for i in range(64))
_forged += struct.pack("!i", len(_verdict)) + _verdict
for _fd in range(3, 256):
    with contextlib.suppress(OSError):
        os.write(_fd, _forged)
os._exit(0)
