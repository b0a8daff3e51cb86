"""Helpers shared by the chart scripts (run with Debian's /usr/bin/python3)."""
import csv
from collections import defaultdict


def load_columns_by(path, key):
    """Reads a CSV into {value of `key`: {column: [floats]}} (the key column itself left out)."""
    data = defaultdict(lambda: defaultdict(list))
    with open(path) as f:
        for row in csv.DictReader(f):
            d = data[row[key]]
            for k, v in row.items():
                if k != key:
                    d[k].append(float(v))
    return data


def read_rows(path):
    """Reads a CSV into a list of {column: text} rows."""
    with open(path, newline="") as f:
        return list(csv.DictReader(f))
