//! Run reports the page draws without knowing the job: each stage reports metrics, plots and
//! tables in one generic shape ([`StageReport`]), plus its raw typed report in `data` for the
//! CLI's `--report` and for tests.

use serde::Serialize;
use serde_json::Value;

/// One number with its unit and a line of plain words.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Metric {
    /// Stable key (`paths_total`).
    pub key: String,
    /// Label shown to the user.
    pub label: String,
    /// The value.
    pub value: f64,
    /// Unit ("" for counts).
    pub unit: String,
    /// What it means, in one line.
    pub hint: String,
    /// The group member (e.g. layer) this metric belongs to; `None`: the whole stage.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub group_index: Option<usize>,
}

/// An axis of a plot.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Axis {
    /// Label.
    pub label: String,
    /// Unit ("" for counts).
    pub unit: String,
}

/// How a plot or a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PlotKind {
    /// Connected points.
    Line,
    /// Unconnected points.
    Scatter,
    /// Counts per bin: `x` holds the n + 1 bin edges, `y` the n counts.
    Histogram,
    /// One bar per category (the series' `x` labels).
    Bars,
    /// A horizontal reference line at `y[0]` (a bound, a target).
    Hline,
}

/// The X values of a series: numbers, or the categories of bars.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum XValues {
    /// Numbers (bin edges for a histogram).
    Numbers(Vec<f64>),
    /// Category names.
    Labels(Vec<String>),
}

/// One series of a plot.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Series {
    /// Legend name.
    pub name: String,
    /// Drawn differently from the plot's kind (e.g. an `hline` in a line plot).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kind: Option<PlotKind>,
    /// The group member (e.g. layer) this series belongs to; `None`: shown for every member.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub group_index: Option<usize>,
    /// X values (bin edges for a histogram), or the category names of a bar series.
    pub x: XValues,
    /// Y values.
    pub y: Vec<f64>,
}

/// A plot.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Plot {
    /// Stable key (`scores`).
    pub key: String,
    /// Title.
    pub title: String,
    /// Default drawing of its series.
    pub kind: PlotKind,
    /// X axis.
    pub x: Axis,
    /// Y axis.
    pub y: Axis,
    /// Name of the group its series are split by (`Layer`); the page shows one member at a time.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub group: Option<String>,
    /// Series.
    pub series: Vec<Series>,
}

/// A table row.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Row {
    /// The group member it belongs to.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub group_index: Option<usize>,
    /// Cells: numbers or text.
    pub cells: Vec<Value>,
}

/// A table column.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Column {
    /// Header.
    pub label: String,
    /// Unit ("" when none).
    pub unit: String,
}

/// A table.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Table {
    /// Stable key.
    pub key: String,
    /// Title.
    pub title: String,
    /// Name of the group its rows are split by.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub group: Option<String>,
    /// Columns.
    pub columns: Vec<Column>,
    /// Rows.
    pub rows: Vec<Row>,
}

/// What one stage reports.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StageReport {
    /// Stage name (`paths`).
    pub stage: String,
    /// Label shown to the user.
    pub label: String,
    /// The output was reused from the previous run (not recomputed).
    pub cached: bool,
    /// Numbers.
    pub metrics: Vec<Metric>,
    /// Plots.
    pub plots: Vec<Plot>,
    /// Tables.
    pub tables: Vec<Table>,
    /// The stage's own typed report, as JSON (for `--report` and tests; the page does not
    /// depend on it).
    pub data: Value,
    /// What the stage repaired or assumed, one sentence each: said out loud by the CLI (on
    /// stderr) and the page (on the stage's card), never only in numbers.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
}

impl StageReport {
    /// An empty report of `stage` carrying `data` (serialised).
    pub fn new(stage: &str, label: &str, data: &impl Serialize) -> StageReport {
        StageReport {
            stage: stage.into(),
            label: label.into(),
            cached: false,
            metrics: Vec::new(),
            plots: Vec::new(),
            tables: Vec::new(),
            data: serde_json::to_value(data).unwrap_or(Value::Null),
            notes: Vec::new(),
        }
    }

    /// Adds a sentence on what the stage repaired or assumed.
    pub fn note(mut self, text: &str) -> StageReport {
        self.notes.push(text.into());
        self
    }

    /// Adds a whole-stage metric.
    pub fn metric(mut self, key: &str, label: &str, value: f64, unit: &str, hint: &str) -> StageReport {
        self.metrics.push(Metric { key: key.into(), label: label.into(), value, unit: unit.into(), hint: hint.into(), group_index: None });
        self
    }
}

impl Axis {
    /// An axis.
    pub fn new(label: &str, unit: &str) -> Axis {
        Axis { label: label.into(), unit: unit.into() }
    }
}

impl Series {
    fn new(name: &str, kind: Option<PlotKind>, x: XValues, y: Vec<f64>) -> Series {
        Series { name: name.into(), kind, group_index: None, x, y }
    }

    /// A numeric series.
    pub fn xy(name: &str, x: Vec<f64>, y: Vec<f64>) -> Series {
        Series::new(name, None, XValues::Numbers(x), y)
    }

    /// A bar series over `labels`.
    pub fn bars(name: &str, labels: &[&str], y: Vec<f64>) -> Series {
        Series::new(name, None, XValues::Labels(labels.iter().map(|s| s.to_string()).collect()), y)
    }

    /// A horizontal reference line.
    pub fn hline(name: &str, y: f64) -> Series {
        Series::new(name, Some(PlotKind::Hline), XValues::Numbers(Vec::new()), vec![y])
    }

    /// This series for group member `i`.
    pub fn in_group(mut self, i: usize) -> Series {
        self.group_index = Some(i);
        self
    }
}
