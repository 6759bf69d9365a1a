// kccd_example_query MODEL.yaml: the closest pair of the model over a braking box around its zero
// state (every joint ±0.1), as a controller would ask every cycle. Exit 0 when the query is Ok.
#include <cstdio>
#include <vector>

#include <kccd/checker.hpp>
#include <kccd/model.hpp>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: kccd_example_query MODEL.yaml\n");
    return 2;
  }
  try {
    const kccd::Model model = kccd::loadModel(argv[1]);
    kccd::Checker checker(model);  // every buffer a query needs, allocated once
    std::vector<double> lower(model.stateSize(), -0.1), upper(model.stateSize(), 0.1);
    const kccd::QueryResult& r = checker.query(lower, upper, kccd::QueryOptions{.type = kccd::QueryType::Closest});
    if (r.status != kccd::Status::Ok) {  // unsafe: stop the robot
      std::printf("status %s: stop\n", kccd::toString(r.status));
      return 3;
    }
    std::printf("%s: %zu pairs, closest %.4f m (a lower bound over the whole box), %s\n", model.name.c_str(),
                model.pairs.size(), r.min_distance, r.collision ? "within the margin" : "clear");
    return 0;
  } catch (const kccd::InputError& e) {  // loading only: the query itself never throws
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }
}
