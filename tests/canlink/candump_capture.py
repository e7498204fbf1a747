"""A candump capture of vcan0 that the CAN VM tests can trust.

start() begins the capture and returns once candump is listening (a SYNC
it has captured), so that nothing the drives and the master do is missed.
candump runs behind on a busy VM. Three things keep its capture whole:
  * a 4 MiB socket receive buffer (-r; root in the VM may exceed rmem_max),
    and -d, which makes candump write a DROPCOUNT line should the kernel
    still drop frames for it (dropped() reads them: a test checks for 0);
  * -D: it goes on when the interface goes down and comes back up (the
    unplug scenarios), instead of exiting;
  * drain(): before it is stopped, a marker frame sent after everything
    else must be written. The marker is a SYNC (COB-ID 0x080, as the DBC
    knows it); the master's own SYNCs look the same, so the marker is told
    from them by its kernel timestamp (candump -L): it is the only one
    stamped after the moment it was sent. Everything else on the bus must
    have stopped first (the master and the drives have exited).
"""
import subprocess
import time

CANDUMP = ["stdbuf", "-oL", "candump", "-L", "-D", "-d", "-r", "4194304",
           "vcan0"]


def start(capture):
    """candump writing vcan0 to the file capture, listening when this
    returns: a SYNC (no drive is up yet to answer it) until one is in the
    file. Returns the process."""
    dump = subprocess.Popen(CANDUMP, stdout=open(capture, "w"))
    for _ in range(100):
        subprocess.run(["cansend", "vcan0", "080#"], check=False)
        time.sleep(0.1)
        with open(capture) as f:
            if "080#" in f.read():
                break
    return dump


def drain(capture, limit=20.0):
    """Send the marker and wait until it is the capture's last line.
    Returns whether it came within limit seconds."""
    sent = time.time()
    subprocess.run(["cansend", "vcan0", "080#"], check=False)
    while time.time() < sent + limit:
        with open(capture) as f:
            lines = f.read().splitlines()
        if lines and lines[-1].endswith(" vcan0 080#"):
            stamp = float(lines[-1].split()[0].strip("()"))
            if stamp >= sent:
                return True
        time.sleep(0.1)
    return False


def dropped(capture):
    """Frames the kernel dropped for candump (its DROPCOUNT lines)."""
    total = 0
    with open(capture) as f:
        for line in f:
            if line.startswith("DROPCOUNT: dropped "):
                total += int(line.split()[2])
    return total
