"""The autograder's steps, run by nbgrader (``nbgrader_config.py``); apart from ``grading.py``, which
every kernel imports, so that a kernel never loads nbgrader and nbformat (seconds)."""

from nbformat import read
from nbformat.v4 import new_output
from nbgrader.preprocessors import NbGraderPreprocessor

from coursework.grading import report


class AfterRun(NbGraderPreprocessor):
    """Once the notebook ran: stderr and a test cell's value (which nbgrader would take as its grade)
    are dropped; the test of a flagged answer fails with the report's lines (0 until the teacher reads
    it), and so does every other test of the notebook, whose results the flagged answer may have bought."""

    release = None  #: the course's release folder (a pathlib.Path), set by nbgrader_config.py

    def preprocess(self, nb, resources):
        ids = resources.get("nbgrader", {})
        path = self.release and self.release / ids.get("assignment", "") / f"{ids.get('notebook')}.ipynb"
        self.flagged = report(nb, read(path, as_version=4) if path and path.is_file() else None)
        return super().preprocess(nb, resources)

    def preprocess_cell(self, cell, resources, index):
        meta = cell.metadata.get("nbgrader", {})
        dropped = ("stderr", "execute_result" if meta.get("grade") else "stderr")
        if cell.cell_type == "code" and meta:
            cell.outputs = [o for o in cell.outputs if o.get("name", o.output_type) not in dropped]
        exercise = meta.get("grade_id", "").removesuffix("_test")
        found = self.flagged.get(exercise, [f"held with {', '.join(self.flagged)}"])  # a flag holds them all
        if meta.get("grade") and self.flagged and cell.cell_type == "code":  # a written answer has no outputs
            why = f"the answer {exercise} is to be reviewed by the teacher: {'; '.join(found)}"
            cell.outputs.append(new_output("error", ename="ToBeReviewed", evalue=why, traceback=[why]))
        return cell, resources


class VerdictOnly(NbGraderPreprocessor):
    """Feedback: a test cell's error, its one-line message only; no cell's printout or traceback
    (any cell may print the kernel's history, which holds the hidden tests)."""

    def preprocess_cell(self, cell, resources, index):
        if cell.cell_type == "code":
            test = cell.metadata.get("nbgrader", {}).get("grade")
            cell.outputs = [o for o in cell.get("outputs", []) if test and o.get("output_type") == "error"]
            for output in cell.outputs:
                output["traceback"] = [f"{output['ename']}: {output['evalue']}"]
        return cell, resources
