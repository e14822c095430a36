"""The study online: a static jsPsych site (``flipstudy export-web``) and its results
back into the study (``flipstudy import-web``).

* :mod:`.site` writes the site; :mod:`.jspsych` fetches the pinned jsPsych packages
  with npm; :mod:`.order` is the Python twin of the site's trial-order rule.
* :mod:`.importer` reads JATOS, Pavlovia and download files into
  ``STUDY/web/responses.csv``.
"""
