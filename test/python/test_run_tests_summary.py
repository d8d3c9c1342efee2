"""scripts/run_tests names every failed case before its last line, so the end of a long CI log says
what failed: the names come from the JUnit files the suites write."""


def test_failed_cases_are_named_with_their_reason(tmp_path, load_script):
    xml = tmp_path / "r.xml"
    xml.write_text(
        '<testsuites><testsuite name="s">'
        '<testcase classname="pkg.Case" name="test_fails"><failure message="AssertionError: 1 != 2&#10;detail">'
        'tb</failure></testcase>'
        '<testcase classname="pkg.Case" name="test_ok"/>'
        '<testcase classname="pkg.Case" name="test_skip"><skipped/></testcase>'
        '<testcase classname="pkg.Case" name="test_errors"><error>Traceback (most recent call last):\n'
        '  File "x.py", line 1\nRuntimeError: boom\n</error></testcase>'
        '</testsuite></testsuites>')
    failed = []
    assert load_script("run_tests").count_junit(xml, "pytest", failed) == (4, 2, 1)
    assert failed == ["pytest: pkg.Case.test_fails: AssertionError: 1 != 2",
                      "pytest: pkg.Case.test_errors: RuntimeError: boom"]


def test_a_rosunit_failure_is_named_by_its_error_not_the_tracebacks_carets(tmp_path, load_script):
    # rosunit writes no message: the error first, then the traceback, whose last line may be Python's carets
    xml = tmp_path / "r.xml"
    xml.write_text(
        '<testsuite name="s"><testcase classname="__main__.T" name="test_a"><failure type="AssertionError">'
        '3 != 1 : goal aborted\n  File "t.py", line 9, in test_a\n    if method() is not None:\n'
        '       ^^^^^^^^\n</failure></testcase></testsuite>')
    failed = []
    assert load_script("run_tests").count_junit(xml, "rostest t.test", failed) == (1, 1, 0)
    assert failed == ["rostest t.test: __main__.T.test_a: 3 != 1 : goal aborted"]


def test_a_suite_without_cases_is_named_when_it_failed(tmp_path, load_script):
    xml = tmp_path / "r.xml"
    xml.write_text('<testsuite name="rostest_x" tests="3" failures="1" errors="1" skipped="0"/>')
    failed = []
    assert load_script("run_tests").count_junit(xml, "rostest x.test", failed) == (3, 2, 0)
    assert len(failed) == 1 and failed[0].startswith("rostest x.test: rostest_x: 2 failed")
