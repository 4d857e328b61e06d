"""What the end-to-end scripts of tests/apps share: running `fivebar`, checking that bad input
gets one error line and the expected exit status, reading a CSV (comment lines skipped) and
rewriting a log."""
import csv
import json
import os
import subprocess


class Cli:
    """Runs one fivebar executable; failures collects what went wrong, one line each."""

    def __init__(self, fivebar):
        self.fivebar = fivebar
        self.failures = []

    def run(self, args):
        p = subprocess.run([self.fivebar] + args, capture_output=True, text=True)
        return p.returncode, p.stdout, p.stderr

    def expect_error(self, status, pattern, args):
        """The run exits `status` with one line `fivebar: error: ...` that contains `pattern`."""
        code, _, err = self.run(args)
        lines = err.strip("\n").split("\n")
        if code != status or len(lines) != 1 or not lines[0].startswith("fivebar: error: ") \
                or pattern not in lines[0]:
            self.failures.append("%s: exit %d, stderr %r (expected %d and '%s')"
                                 % (args, code, err, status, pattern))


    def identify(self, name, scene, log, out, extra=()):
        """`fivebar identify scene --log log --out out` (plus extra): its exit status and
        identification.json ({} with a failure noted when none was written)."""
        code, _, err = self.run(["identify", scene, "--log", log, "--out", out] + list(extra))
        path = os.path.join(out, "identification.json")
        if not os.path.exists(path):
            self.failures.append("%s: no identification.json (exit %d: %s)" % (name, code, err))
            return code, {}
        with open(path) as f:
            return code, json.load(f)


def rewrite_log(src, dst, change):
    """The log src with change(header, rows) applied (rows: lists of cells; it returns the rows
    to write), written to dst with src's comment lines; returns dst."""
    with open(src) as f:
        lines = f.read().splitlines()
    head = [l for l in lines if l.startswith("#")]
    body = [l for l in lines if not l.startswith("#")]
    rows = change(body[0].split(","), [r.split(",") for r in body[1:]])
    with open(dst, "w") as f:
        f.write("\n".join(head + [body[0]] + [",".join(r) for r in rows]) + "\n")
    return dst


def column(name, change):
    """A rewrite_log change: every value v of the column `name` replaced by change(v)."""
    def rewrite(cols, rows):
        k = cols.index(name)
        for r in rows:
            r[k] = repr(change(float(r[k])))
        return rows
    return rewrite


def zero(offset):
    """A rewrite_log change: theta1 read `offset` rad more than the true angle (an encoder's
    zero off)."""
    return column("theta1", lambda v: v + offset)


def shift_torques(k):
    """A rewrite_log change: torques that lag the angles by k samples (k < 0: lead); row i's
    torques are the true ones of row i - k, the rows without one dropped."""
    def change(cols, rows):
        ti = [j for j, c in enumerate(cols) if c.startswith("tau")]
        out = []
        for i in range(max(0, k), len(rows) + min(0, k)):
            r = list(rows[i])
            for j in ti:
                r[j] = rows[i - k][j]
            out.append(r)
        return out
    return change


def read_csv(path):
    with open(path) as f:
        return list(csv.DictReader(l for l in f if not l.startswith("#")))


def write_hold_move(path, noise=None):
    """A five-bar motion file t,theta1,theta2 at 1 kHz: both cranks at pi/2 for 0.5 s, theta1 a
    quintic move of 0.5 rad in 0.5 s (peak 1.9 rad/s), held 0.5 s; `noise`: a random.Random and
    a std [rad] added to every angle, or None."""
    import math
    with open(path, "w") as f:
        f.write("t,theta1,theta2\n")
        for i in range(1501):
            t = i * 1e-3
            u = min(max((t - 0.5) / 0.5, 0.0), 1.0)
            th = math.pi / 2 + 0.5 * (10 * u**3 - 15 * u**4 + 6 * u**5)
            e1, e2 = (noise[0].gauss(0, noise[1]), noise[0].gauss(0, noise[1])) if noise else (0, 0)
            f.write("%.17g,%.17g,%.17g\n" % (t, th + e1, math.pi / 2 + e2))
