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


# The autograder's Execute, guarded. A student's cell runs in the kernel before the tests, so one
# that hooks into the kernel (an input transformer that empties the test cells, an event handler,
# a trace function, replaced built-ins or shell methods) or ends it (os._exit, a crash) could make
# the tests pass or never run, and a test that never ran counts as passed. So:
# - an answer cell whose code reaches for a kernel hook (vo_lib.grading.kernel_hooks) is not run;
#   it and its test show why, and the exercise scores 0 until the teacher looks at it by hand;
# - the kernel's hooks are compared before and after every answer cell (vo_lib.grading.kernel_state,
#   read as a user expression, which no transformer or handler sees), and every test cell, whose
#   calls of an answer's functions may change them too (the tools the next hidden test loads, say);
#   from a change on, no test runs and each says where the kernel was changed, and a test cell
#   that changed it fails;
# - a kernel that dies stops the notebook, not the batch: every later cell says in which cell it
#   died, and scores 0;
# - a cell stopped by the timeout says which cell it was.
import ast  # noqa: E402

from nbclient.exceptions import DeadKernelError  # noqa: E402
from nbformat.notebooknode import NotebookNode  # noqa: E402
from nbgrader.converters import Autograde  # noqa: E402
from nbgrader.preprocessors import Execute  # noqa: E402

import vo_lib.grading  # noqa: E402
from vo_lib.grading import cell_label, kernel_hooks  # noqa: E402

# read afresh from its file at every call: an answer that replaced the imported module's function
# (by one that returns a copy of the state it saw) has no hold on it
STATE = f"__import__('runpy').run_path({vo_lib.grading.__file__!r})['kernel_state']()"


def _error(ename, evalue):
    return NotebookNode(output_type="error", ename=ename, evalue=evalue, traceback=[f"{ename}: {evalue}"])


class GuardedExecute(Execute):
    """nbgrader's Execute that refuses kernel hooks, survives a dead kernel and names timed-out cells."""

    def preprocess(self, nb, resources=None, km=None):
        self.stopped = None  # why no later test may run: a hook found, a dead kernel
        self.refused = {}  # grade_id of an answer not run -> why
        return super().preprocess(nb, resources, km)

    def preprocess_cell(self, cell, resources, index):
        if cell.cell_type != "code" or not cell.source.strip():
            return cell, self.resources
        meta = cell.metadata.get("nbgrader", {})
        grade_id = meta.get("grade_id", "")
        if self.stopped:
            cell.outputs = [_error("NotRun", f"not run: {self.stopped}")]
            return cell, self.resources
        if grade_id.endswith("_test") and grade_id.removesuffix("_test") in self.refused:
            cell.outputs = [_error("KernelHook", self.refused[grade_id.removesuffix("_test")])]
            return cell, self.resources
        answer = bool(meta.get("solution"))
        if answer and (hooks := kernel_hooks(cell.source)):
            self.refused[grade_id] = (
                f"the answer {grade_id} was not run: it reaches into the kernel "
                f"({', '.join(dict.fromkeys(hooks))}), which could change the tests; 0 points "
                "until the teacher has looked at it"
            )
            cell.outputs = [_error("KernelHook", self.refused[grade_id])]
            return cell, self.resources
        label = cell_label(cell, index)
        self.error_on_timeout = {
            "ename": "CellTimeoutError",
            "evalue": f"{label} was still running after {self.timeout} s and was stopped",
            "traceback": [
                f"CellTimeoutError: {label} was still running after {self.timeout} s and was stopped"
            ],
        }
        guarded = answer or bool(meta.get("grade"))  # an answer, or a test that calls one
        try:
            before = self._kernel_state() if guarded else None
            cell, resources = super().preprocess_cell(cell, resources, index)
            after = self._kernel_state() if guarded else None
        except DeadKernelError:
            self.stopped = f"the kernel died in {label}"
            cell.outputs = list(cell.get("outputs", [])) + [
                _error("KernelDied", f"the kernel died in {label}")
            ]
            return cell, self.resources
        changed = [what for what in before or {} if before[what] != (after or {}).get(what)]
        if changed:
            self.stopped = f"{label} changed the kernel ({', '.join(changed)})"
            cell.outputs.append(_error("KernelHook", self.stopped))
        return cell, resources

    def _kernel_state(self):
        """:func:`vo_lib.grading.kernel_state` in the kernel, as a user expression."""
        msg_id = self.kc.execute("", silent=True, store_history=False, user_expressions={"state": STATE})
        reply = self.wait_for_reply(msg_id) or {}
        result = reply.get("content", {}).get("user_expressions", {}).get("state", {})
        text = result.get("data", {}).get("text/plain", "")
        try:
            return ast.literal_eval(text)
        except (ValueError, SyntaxError):  # the expression failed: that, too, is a change
            return {"state": text or repr(result)}


c.Autograde.autograde_preprocessors = [  # nbgrader's own list, with GuardedExecute for Execute
    GuardedExecute if p is Execute else p
    for p in Autograde.class_traits()["autograde_preprocessors"].make_dynamic_default()
]
c.ClearSolutions.code_stub = {"python": "# YOUR CODE HERE\nraise NotImplementedError()"}
c.ClearSolutions.text_stub = "YOUR ANSWER HERE"


# Feedback shows what failed, not how it was tested: the hidden tests are taken out of the graded
# notebook (ClearHiddenTests) and a failed test's traceback, which would quote the failing line, is
# cut down to its message ("AssertionError: the gain of another update ..."), which the tests word
# so as to say what is wrong without giving the answer.
from nbconvert.preprocessors import CSSHTMLHeaderPreprocessor  # noqa: E402
from nbgrader.preprocessors import ClearHiddenTests, GetGrades, NbGraderPreprocessor  # noqa: E402


class GetGradesSayingToBeGraded(GetGrades):
    """nbgrader's GetGrades, and a part still to be marked by hand says so in the feedback."""

    def _get_score(self, cell, resources):
        super()._get_score(cell, resources)
        meta = cell.metadata["nbgrader"]
        grade = self.gradebook.find_grade(
            meta["grade_id"], self.notebook_id, self.assignment_id, self.student_id
        )
        if grade.needs_manual_grade:
            cell.source += (
                f"\n\n**To be graded** by hand ({grade.max_score:g} points): the score is not final."
            )


class MessageOnlyTracebacks(NbGraderPreprocessor):
    """Replace the traceback of every failed test cell by its one-line message."""

    def preprocess_cell(self, cell, resources, index):
        if cell.cell_type == "code" and cell.metadata.get("nbgrader", {}).get("grade"):
            for output in cell.get("outputs", []):
                if output.get("output_type") == "error":
                    output["traceback"] = [f"{output['ename']}: {output['evalue']}"]
        return cell, resources


c.GenerateFeedback.preprocessors = [
    GetGradesSayingToBeGraded,
    ClearHiddenTests,
    MessageOnlyTracebacks,
    CSSHTMLHeaderPreprocessor,
]


# grades.csv gains a column "to_be_graded": the points of each submission still to be marked by
# hand (a written part), so that a provisional score is not read as the final one.
from nbgrader.plugins.export import CsvExportPlugin  # noqa: E402


class CsvExportSayingToBeGraded(CsvExportPlugin):
    """nbgrader's CSV export with a column of the points still to be graded by hand."""

    def export(self, gradebook):
        import csv

        from nbgrader.api import MissingEntry

        super().export(gradebook)
        dest = self.to or "grades.csv"
        with open(dest, newline="") as fh:
            rows = list(csv.DictReader(fh))
        if not rows:
            return
        for row in rows:
            try:
                submission = gradebook.find_submission(row["assignment"], row["student_id"])
            except MissingEntry:  # not submitted: nothing to grade
                row["to_be_graded"] = ""
                continue
            pending = [g.max_score for nb in submission.notebooks for g in nb.grades if g.needs_manual_grade]
            row["to_be_graded"] = f"{sum(pending):g}"
        with open(dest, "w", newline="") as fh:
            writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
            writer.writeheader()
            writer.writerows(rows)


c.ExportApp.plugin_class = CsvExportSayingToBeGraded
