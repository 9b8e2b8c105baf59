// peritwin-snapshot-png: renders a damage snapshot CSV (x_m,y_m,damage — as written by
// peritwin-validate) to a PNG damage map.
//   peritwin-snapshot-png SNAPSHOT.csv OUT.png DX
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "outputs/damage_png.h"

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: peritwin-snapshot-png SNAPSHOT.csv OUT.png DX\n");
    return 2;
  }
  std::ifstream in(argv[1]);
  if (!in) {
    std::fprintf(stderr, "peritwin-snapshot-png: cannot read %s\n", argv[1]);
    return 2;
  }
  std::vector<double> x, y, d;
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    std::istringstream row(line);
    double a, b, c;
    char comma;
    if (row >> a >> comma >> b >> comma >> c) {
      x.push_back(a);
      y.push_back(b);
      d.push_back(c);
    }
  }
  peritwin::outputs::write_damage_png(argv[2], x, y, d, std::stod(argv[3]));
  return 0;
}
