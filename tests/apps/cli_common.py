"""What the end-to-end scripts of tests/apps share: running `fivebar`, checking that bad input
gets one error line and the expected exit status, and reading a CSV (comment lines skipped)."""
import csv
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


def read_csv(path):
    with open(path) as f:
        return list(csv.DictReader(l for l in f if not l.startswith("#")))
