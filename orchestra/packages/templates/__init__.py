"""jinja2 templates for `orchestra create-pkg` (a package so that installs ship the files)."""
