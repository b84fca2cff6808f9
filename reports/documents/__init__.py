"""The PDF documents: a test event's report and the comparison of several.

They read (through the selectors) and draw (reports.charts) but store nothing;
reports.services.generation keeps what they make.
"""
