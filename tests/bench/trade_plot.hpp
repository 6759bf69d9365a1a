// The speed/accuracy plot of bench_trade (OpenCV, PNG): one cell per scene and box set, each with
// two panels over the same x axis (distances query time, log scale): looseness p90 over the pairs
// whose bound is within the band above the margin above, the false-alarm rate below; one line per
// sweep mode through its point budgets.
#pragma once

#include <string>
#include <vector>

namespace kccd::bench {

struct TradePoint {
  int budget = 0;
  double distances_us = 0.0;
  double looseness_p90_mm = 0.0;
  double false_alarm_pct = 0.0;
};

struct TradeSeries {
  std::string label;  ///< e.g. the sweep mode
  std::vector<TradePoint> points;
};

struct TradeCell {
  std::string title;  ///< scene and box set
  std::vector<TradeSeries> series;
};

/// Draws `cells` in a grid `columns` wide and writes a PNG. Returns false with `error` set when
/// the file cannot be written.
bool writeTradePlot(const std::string& path, const std::string& title, const std::vector<TradeCell>& cells, int columns,
                    std::string& error);

}  // namespace kccd::bench
