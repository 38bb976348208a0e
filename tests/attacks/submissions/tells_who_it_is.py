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
print(f"who: folder {os.getcwd()} {oct(os.stat('.').st_mode & 0o777)} home {os.environ.get('HOME')} "
      f"environment {','.join(sorted(os.environ))}", flush=True)


def generate_rays(camera, width, height, pixel_x, pixel_y, u):
    raise NotImplementedError("generate_rays")
