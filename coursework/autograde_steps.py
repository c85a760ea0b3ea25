"""The autograder's steps, run by nbgrader (``nbgrader_config.py``); apart from ``grading.py``, which
every kernel imports, so that a kernel never loads nbgrader and nbformat (seconds)."""

import nbformat
from nbgrader.preprocessors import NbGraderPreprocessor

from coursework.grading import report


class AfterRun(NbGraderPreprocessor):
    """Once the notebook ran: stderr (a warning, a progress bar) is dropped and never costs a mark,
    and the test of a flagged answer fails with the report's lines (0 until the teacher reads it);
    so does every other test of that notebook, whose results the flagged answer may have bought."""

    def preprocess(self, nb, resources):
        self.flagged = report(nb)
        return super().preprocess(nb, resources)

    def preprocess_cell(self, cell, resources, index):
        if cell.cell_type == "code" and cell.metadata.get("nbgrader"):
            cell.outputs = [o for o in cell.get("outputs", []) if o.get("name") != "stderr"]
        exercise = cell.metadata.get("nbgrader", {}).get("grade_id", "").removesuffix("_test")
        found = self.flagged.get(exercise, [f"held with {', '.join(self.flagged)}"])  # a flag holds them all
        if cell.metadata.get("nbgrader", {}).get("grade") and self.flagged:
            why = f"the answer {exercise} is to be reviewed by the teacher: {'; '.join(found)}"
            error = dict(ename="ToBeReviewed", evalue=why, traceback=[f"ToBeReviewed: {why}"])
            cell.outputs.append(nbformat.v4.new_output("error", **error))
        return cell, resources


class VerdictOnly(NbGraderPreprocessor):
    """Feedback of a test cell: its error's one-line message, no traceback and nothing it printed."""

    def preprocess_cell(self, cell, resources, index):
        if cell.cell_type == "code" and cell.metadata.get("nbgrader", {}).get("grade"):
            cell.outputs = [o for o in cell.get("outputs", []) if o.get("output_type") == "error"]
            for output in cell.outputs:
                output["traceback"] = [f"{output['ename']}: {output['evalue']}"]
        return cell, resources
