"""nbgrader's settings for the vo-notebooks course folder that ``coursework/build.py`` writes."""

import atexit
import os
import shutil
import tempfile

c = get_config()  # noqa: F821 (nbgrader provides get_config when it reads this file)

c.CourseDirectory.course_id = "vo-notebooks"
# Notebooks that render a sequence or run a sweep have cells of a minute or two on a busy machine;
# a cell still running after 10 minutes is stopped and fails as "CellTimeoutError" in its own
# output, so the graded notebook names it. (nbgrader's Execute always goes on after an error: an
# unanswered exercise raises and the rest of the notebook still runs and is graded.)
c.Execute.timeout = 600
# Kernels talk over Unix sockets in a private folder, not TCP ports: several kernels started at
# once on a busy machine cannot race for a port and stall.
_sockets = tempfile.mkdtemp(prefix="vo-nbgrader-")
atexit.register(shutil.rmtree, _sockets, True)
c.KernelManager.transport = "ipc"
c.KernelManager.ip = os.path.join(_sockets, "kernel")
c.ClearSolutions.code_stub = {"python": "# YOUR CODE HERE\nraise NotImplementedError()"}
c.ClearSolutions.text_stub = "YOUR ANSWER HERE"
