"""nbgrader's settings for the vo-notebooks course folder that ``coursework/build.py`` writes."""

c = get_config()  # noqa: F821 (nbgrader provides get_config when it reads this file)

c.CourseDirectory.course_id = "vo-notebooks"
# Notebooks that render a sequence or run a sweep have cells of a minute or two on a busy machine.
c.Execute.timeout = 600
# An unanswered exercise raises; the rest of the notebook still runs and is graded.
c.Execute.allow_errors = True
c.ClearSolutions.code_stub = {"python": "# YOUR CODE HERE\nraise NotImplementedError()"}
c.ClearSolutions.text_stub = "YOUR ANSWER HERE"
