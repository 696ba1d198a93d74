"""Shows the fuzz test's outcome counts at the end of every run (also under xdist, where a test's
own output is not shown): the test records them as a user property of its report."""


def pytest_terminal_summary(terminalreporter):
    for reports in terminalreporter.stats.values():
        for report in reports:
            for name, value in getattr(report, "user_properties", ()):
                if name == "fuzz":
                    terminalreporter.write_line(value)
