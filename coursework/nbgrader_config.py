"""nbgrader's settings for the course folder that ``coursework/build.py`` writes (see docs/course.md)."""

import csv
import json
import os
import pathlib
import sys
import tempfile

from IPython.paths import get_ipython_dir
from nbconvert.preprocessors import CSSHTMLHeaderPreprocessor as StyleSheet
from nbgrader.converters import Autograde
from nbgrader.plugins.export import CsvExportPlugin
from nbgrader.preprocessors import ClearHiddenTests, Execute, GetGrades

c = get_config()  # noqa: F821 (nbgrader provides get_config when it reads this file)
here = pathlib.Path(__file__).resolve().parent
in_course = here.name != "coursework"  # not the repository's own copy
tools = str(here if in_course else here.parent)  # `from coursework import grading`, here and in kernels
sys.path.insert(0, tools)
os.environ["PYTHONPATH"] = os.pathsep.join(filter(None, [tools, os.environ.get("PYTHONPATH")]))
os.environ["VO_LIB_HEADLESS"] = "1"  # no widget waits for a browser that is not there
import vo_lib  # noqa: E402, F401  (sets OPENBLAS_CORETYPE for the grading kernels: same marks on AVX2 CPUs)
from coursework import autograde_steps, grading  # noqa: E402

c.CourseDirectory.course_id = "vo-notebooks"
c.Execute.timeout = 600  # a cell still running after 10 minutes fails as CellTimeoutError
# Kernels talk over Unix sockets in a private folder: kernels started at once cannot race for a port.
sockets = (sockets_folder := tempfile.TemporaryDirectory(prefix="vo-nbgrader-")).name  # gone at exit
c.KernelManager.transport = "ipc"
c.KernelManager.ip = os.path.join(sockets, "kernel")

# Isolation: the kernels see source/, release/, the submissions, the feedback, the gradebook and every
# path of hidden.txt (build.py's list) or VO_HIDDEN empty, the grader's files read-only (docs/course.md).
if in_course and grading.can_isolate():
    hidden = [str(here / n) for n in "source release submitted autograded feedback gradebook.db".split()]
    listed = (here / "hidden.txt").read_text().splitlines() if (here / "hidden.txt").is_file() else []
    hidden += [p for p in [*listed, *os.environ.get("VO_HIDDEN", "").split(os.pathsep)] if p]
    hidden.append(get_ipython_dir())  # IPython's history of the teacher's sessions: solutions too
    argv = grading.isolated_kernel(hidden, [str(here / "coursework"), str(here / "nbgrader_config.py")])
    spec = {"argv": argv, "display_name": "Python 3", "language": "python"}
    (kernel_folder := pathlib.Path(sockets) / "kernels" / "python3").mkdir(parents=True)
    (kernel_folder / "kernel.json").write_text(json.dumps(spec))
    os.environ["JUPYTER_PATH"] = os.pathsep.join(filter(None, [sockets, os.environ.get("JUPYTER_PATH")]))
elif in_course:
    print("nbgrader_config.py: unshare -rm is not allowed here: kernels run NOT isolated", file=sys.stderr)

# After the notebook ran, stderr and tests' values are dropped, a flagged answer's test fails (its lines).
autograde_steps.AfterRun.release = here / "release" if in_course else None  # a cell changed from it: read
steps = Autograde.class_traits()["autograde_preprocessors"].make_dynamic_default()
at = steps.index(Execute) + 1
c.Autograde.autograde_preprocessors = [*steps[:at], autograde_steps.AfterRun, *steps[at:]]


class ToBeGraded(GetGrades):
    """nbgrader's GetGrades; in the feedback, a part still to be marked by hand says so."""

    def _get_score(self, cell, resources):
        super()._get_score(cell, resources)
        ids = (cell.metadata["nbgrader"]["grade_id"], self.notebook_id, self.assignment_id, self.student_id)
        if (grade := self.gradebook.find_grade(*ids)).needs_manual_grade:
            cell.source += f"\n\n**To be graded** by hand ({grade.max_score:g} points): not final."


# Feedback shows each test's verdict and one-line message: no test source, traceback or printout.
c.GenerateFeedback.preprocessors = [ToBeGraded, ClearHiddenTests, autograde_steps.VerdictOnly, StyleSheet]


class CsvExportToBeGraded(CsvExportPlugin):
    """nbgrader's grades.csv and a column "to_be_graded": the points still to be marked by hand."""

    def export(self, gradebook):
        super().export(gradebook)
        sent = {(s.name, s.student_id): s.notebooks for a in gradebook.assignments for s in a.submissions}
        with open(dest := self.to or "grades.csv", newline="") as fh:
            rows, fields = list(table := csv.DictReader(fh)), [*(table.fieldnames or []), "to_be_graded"]
        for row in rows:  # nothing to grade for an assignment not submitted
            notebooks = sent.get((row["assignment"], row["student_id"]))
            pending = [g.max_score for n in notebooks or [] for g in n.grades if g.needs_manual_grade]
            row["to_be_graded"] = "" if notebooks is None else f"{sum(pending):g}"
        with open(dest, "w", newline="") as fh:
            (writer := csv.DictWriter(fh, fields)).writeheader()
            writer.writerows(rows)


c.ExportApp.plugin_class = CsvExportToBeGraded
