"""The version has one home, ``bouncing_ball.__version__``; the citation file and the
changelog's newest release repeat it and must agree with it."""

import re
from pathlib import Path

import yaml

import bouncing_ball

REPOSITORY = Path(__file__).resolve().parents[2]

# a released version's heading in Keep a Changelog form: "## [0.2.0] - 2026-11-25"
RELEASE_HEADING = re.compile(r"^## \[(\d+\.\d+\.\d+)\] - \d{4}-\d{2}-\d{2}$", re.MULTILINE)


def test_citation_file_names_the_package_version():
    citation = yaml.safe_load((REPOSITORY / "CITATION.cff").read_text())
    assert str(citation["version"]) == bouncing_ball.__version__


def test_newest_changelog_release_is_the_package_version():
    changelog = (REPOSITORY / "CHANGELOG.md").read_text()
    releases = RELEASE_HEADING.findall(changelog)
    assert releases, "CHANGELOG.md has no '## [x.y.z] - YYYY-MM-DD' heading"
    assert releases[0] == bouncing_ball.__version__
