"""Not an attack: at import, print what the student's process is (its user, groups, the
kernel's flags on it, its network devices, where it runs), for the tests of the student
user. Every line starts with "who: "."""

import os
from pathlib import Path

status = dict(line.split(":\t", 1) for line in Path("/proc/self/status").read_text().splitlines()
              if ":\t" in line)
print(f"who: uid {os.getuid()} {os.geteuid()} gid {os.getgid()} groups {os.getgroups()}", flush=True)
print(f"who: seccomp {status['Seccomp'].strip()} no_new_privs {status['NoNewPrivs'].strip()} "
      f"capabilities {status['CapEff'].strip()}", flush=True)
devices = [line.split(":")[0].strip() for line in Path("/proc/self/net/dev").read_text().splitlines()[2:]]
print(f"who: network {','.join(devices)}", flush=True)
print(f"who: processes {sorted(int(p) for p in os.listdir('/proc') if p.isdigit())} pid {os.getpid()}",
      flush=True)
import ctypes  # noqa: E402

_libc = ctypes.CDLL(None, use_errno=True)
for _name, _flag in (("user", 0x10000000), ("mount", 0x20000), ("network", 0x40000000)):
    _done = _libc.unshare(_flag)
    print(f"who: unshare-{_name} {_done} errno {ctypes.get_errno()}", flush=True)
import ptlab  # noqa: E402

print(f"who: ptlab {Path(ptlab.__file__).parent} holds {','.join(sorted(os.listdir(Path(ptlab.__file__).parent)))}",
      flush=True)
print(f"who: folder {os.getcwd()} {oct(os.stat('.').st_mode & 0o777)} home {os.environ.get('HOME')} "
      f"environment {','.join(sorted(os.environ))}", flush=True)


def generate_rays(camera, width, height, pixel_x, pixel_y, u):
    raise NotImplementedError("generate_rays")
