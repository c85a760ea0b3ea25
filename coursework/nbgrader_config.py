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
