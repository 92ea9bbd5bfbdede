"""The closed loop brought up, run, recorded and analysed: the paper's experiments and the operator's commands."""
from swim_ros.exports import lazy_exports

#: the public names by module, each imported on first use
__all__, __getattr__ = lazy_exports(__name__, {
    "analysis": ("analyze_bag", "measures", "run_analysis", "summary_table"),
    "bag": ("BagError", "BagWriter", "bag_info", "read_messages", "read_topics"),
    "experiments": ("Experiment", "paper_experiments", "compare", "results_table"),
    "reports": ("RunReport", "ExperimentsSummary", "ReportError", "run_failures"),
    "run_record": ("RecordedBag", "read_bag"),
    "statistics": ("NormStatistics", "PairedChange", "Spread"),
})
