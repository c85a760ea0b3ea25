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


# The course's grading tools (coursework/grading.py, beside this file in the course folder), for
# this file and for the hidden tests, which run in the kernels it starts: `from coursework import
# grading`.
import pathlib  # noqa: E402
import sys  # noqa: E402

_here = pathlib.Path(__file__).resolve().parent
_tools = str(_here.parent if _here.name == "coursework" else _here)
sys.path.insert(0, _tools)
os.environ["PYTHONPATH"] = os.pathsep.join(filter(None, [_tools, os.environ.get("PYTHONPATH")]))

import json  # noqa: E402

from coursework import grading as _grading  # noqa: E402

# The kernels run isolated: what a student's code can read must not include the solutions. Each
# kernel starts in its own mount namespace where the course's solutions and tests (source/), the
# release, the other submissions, the feedback and the gradebook are empty, and so is every path
# listed in VO_HIDDEN beforehand (a checkout of the notebooks, say): see docs/course.md. The
# kernel spec "python3" of a private Jupyter path starts it through coursework/grading.py.
_hidden = [str(_here / name) for name in ("source", "release", "submitted", "feedback", "gradebook.db")]
if _here.name != "coursework" and _grading.can_isolate():
    os.environ["VO_HIDDEN"] = os.pathsep.join(
        [*_hidden, *filter(None, os.environ.get("VO_HIDDEN", "").split(os.pathsep))]
    )
    _spec = pathlib.Path(_sockets) / "kernels" / "python3"
    _spec.mkdir(parents=True)
    _launcher = [sys.executable, _grading.__file__, "--kernel", "{connection_file}"]
    (_spec / "kernel.json").write_text(
        json.dumps({"argv": _launcher, "display_name": "Python 3", "language": "python"})
    )
    os.environ["JUPYTER_PATH"] = os.pathsep.join(filter(None, [_sockets, os.environ.get("JUPYTER_PATH")]))
elif _here.name != "coursework":
    print("nbgrader_config.py: unshare -rm is not allowed here: kernels run NOT isolated", file=sys.stderr)

from nbgrader.converters import Autograde  # noqa: E402
from nbgrader.preprocessors import ClearHiddenTests, Execute, GetGrades  # noqa: E402

from coursework.grading import QuietStderr, ToBeReviewed, VerdictOnly  # noqa: E402

# After the notebook ran: stderr (warnings, progress bars) is dropped from graded cells, and the
# test of an answer the integrity report flags fails with the report's lines (0 points until the
# teacher has read the answer and graded it by hand).
_steps = Autograde.class_traits()["autograde_preprocessors"].make_dynamic_default()
_at = _steps.index(Execute) + 1
c.Autograde.autograde_preprocessors = [*_steps[:_at], QuietStderr, ToBeReviewed, *_steps[_at:]]
c.ClearSolutions.code_stub = {"python": "# YOUR CODE HERE\nraise NotImplementedError()"}
c.ClearSolutions.text_stub = "YOUR ANSWER HERE"


# Feedback shows what failed, not how it was tested: the hidden tests are taken out of the graded
# notebook (ClearHiddenTests), and a test cell keeps only its error, cut down to its one-line
# message ("AssertionError: the gain of another update ..."), not the traceback (which would quote
# the failing line) nor anything the answer printed while the test ran.
from nbconvert.preprocessors import CSSHTMLHeaderPreprocessor  # noqa: E402


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


c.GenerateFeedback.preprocessors = [
    GetGradesSayingToBeGraded,
    ClearHiddenTests,
    VerdictOnly,
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
