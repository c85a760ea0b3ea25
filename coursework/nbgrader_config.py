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
# The kernels nbgrader starts inherit this: vo_lib's offer() then shows no widget, which with no
# browser to answer it could only wait.
os.environ["VO_LIB_HEADLESS"] = "1"
c.ClearSolutions.code_stub = {"python": "# YOUR CODE HERE\nraise NotImplementedError()"}
c.ClearSolutions.text_stub = "YOUR ANSWER HERE"


# Feedback shows what failed, not how it was tested: the hidden tests are taken out of the graded
# notebook (ClearHiddenTests) and a failed test's traceback, which would quote the failing line, is
# cut down to its message ("AssertionError: the gain of another update ..."), which the tests word
# so as to say what is wrong without giving the answer.
from nbconvert.preprocessors import CSSHTMLHeaderPreprocessor  # noqa: E402
from nbgrader.preprocessors import ClearHiddenTests, GetGrades, NbGraderPreprocessor  # noqa: E402


class MessageOnlyTracebacks(NbGraderPreprocessor):
    """Replace the traceback of every failed test cell by its one-line message."""

    def preprocess_cell(self, cell, resources, index):
        if cell.cell_type == "code" and cell.metadata.get("nbgrader", {}).get("grade"):
            for output in cell.get("outputs", []):
                if output.get("output_type") == "error":
                    output["traceback"] = [f"{output['ename']}: {output['evalue']}"]
        return cell, resources


c.GenerateFeedback.preprocessors = [
    GetGrades,
    ClearHiddenTests,
    MessageOnlyTracebacks,
    CSSHTMLHeaderPreprocessor,
]
