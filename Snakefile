# icosim: replication of Schweizer et al., "Implicit co-simulation methods" (stability,
# convergence and the double pendulum), and chains of N units beyond it.  `snakemake -c2` builds everything configured.
from snakemake.utils import min_version

min_version("8.0")


configfile: "config/config.yaml"
configfile: "config/stability.yaml"
configfile: "config/convergence.yaml"
configfile: "config/pendulum.yaml"
configfile: "config/fmi.yaml"
configfile: "config/chains.yaml"
configfile: "config/signals.yaml"
configfile: "config/peers.yaml"


include: "workflow/rules/common.smk"
include: "workflow/rules/stability.smk"
include: "workflow/rules/convergence.smk"
include: "workflow/rules/pendulum.smk"
include: "workflow/rules/fmi.smk"
include: "workflow/rules/chains.smk"
include: "workflow/rules/signals.smk"
include: "workflow/rules/peers.smk"
include: "workflow/rules/report.smk"


rule all:
    default_target: True
    input:
        ALL_TARGETS,
        REPORT_HTML,


include: "workflow/rules/integrity.smk"
