"""How text, tables and units are typeset: Markdown, LaTeX and matplotlib mathtext.

Markdown pipe tables, LaTeX tables for papers (escaped text, typeset units, numbers, booktabs
rules), the same units for matplotlib's labels, and the statsmodels-style summaries the fitted
models and the noise fit print.

A bottom layer beside :mod:`fosmodel.core`: it imports nothing else of fosmodel.
"""
