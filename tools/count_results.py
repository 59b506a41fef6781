#!/usr/bin/env python3
"""Prints 'N passed, N failed' over every JUnit XML file under a directory (catkin test results)."""
import glob
import os
import sys
import xml.etree.ElementTree as ET


def count(results_dir):
    passed = failed = 0
    for path in glob.glob(os.path.join(results_dir, '**', '*.xml'), recursive=True):
        try:
            root = ET.parse(path).getroot()
        except ET.ParseError:
            failed += 1  # a results file cut short counts as a failure, not as nothing
            continue
        for case in root.iter('testcase'):
            if case.find('failure') is not None or case.find('error') is not None:
                failed += 1
            elif case.find('skipped') is None:
                passed += 1
    return passed, failed


if __name__ == '__main__':
    p, f = count(sys.argv[1])
    print('%d passed, %d failed' % (p, f))
