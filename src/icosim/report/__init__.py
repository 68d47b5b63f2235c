"""The self-contained HTML report, built from generated files only (no Snakemake here).

Each part renders one *section* (an HTML fragment with its figures embedded as
base64 PNG) from its datasets, claim verdicts and configuration; the page
assembles the sections with provenance into ``reports/icosim_report.html``.

=====================  ==============================================
module                 holds
=====================  ==============================================
:mod:`.html`           building blocks: escaping, tables, figures, sections, page
:mod:`.claims`         the claims table
:mod:`.stability`      the stability section (Figs. 9-20)
:mod:`.convergence`    the convergence section (Figs. 21-23, work-precision)
:mod:`.pendulum`       the pendulum section (Sect. 4, Figs. 6-8)
:mod:`.page`           the page: sections in order, navigation, provenance
=====================  ==============================================
"""
