# common.py: what the fuzzers share: running one case of the strata CLI and judging it.
import os, subprocess, sys, time

# The exit codes the sanitizer stage uses (tools/run_tests.sh): a report is 86 or 87, never 0-2.
SANITIZER_ENV = dict(os.environ, ASAN_OPTIONS='detect_leaks=1:exitcode=86',
                     UBSAN_OPTIONS='print_stacktrace=1:exitcode=87')


class Tally:
  """Exit codes seen (per label) and the cases reported."""

  def __init__(self):
    self.hist = {}
    self.bad = 0

  def run(self, label, case, argv, slow, output=None):
    """Runs argv; reports `case` (returns False) when the exit code is not 0, 1 or 2 (a crash, a
    sanitizer report, a timeout at 5 x slow), when it took over `slow` seconds, or when a staging
    file of `output` (the command's output name) is left in the directory."""
    t = time.time()
    try:
      p = subprocess.run(argv, capture_output=True, timeout=5 * slow, env=SANITIZER_ENV)
      rc, err = p.returncode, p.stderr
    except subprocess.TimeoutExpired:
      rc, err = 'timeout', b''
    dt = time.time() - t
    self.hist[(label, rc)] = self.hist.get((label, rc), 0) + 1
    left = [f for f in os.listdir('.') if output and output in f and f != output]
    if rc in (0, 1, 2) and dt <= slow and not left:
      return True
    self.bad += 1
    print('BAD', case, label, rc, '%.1fs' % dt, left, err[-800:].decode(errors='replace').replace('\n', ' | '))
    sys.stdout.flush()
    return False

  def summary(self, n):
    print('done', n, 'bad', self.bad, self.hist)


def remove(*paths):
  for p in paths:
    if os.path.exists(p):
      os.remove(p)
