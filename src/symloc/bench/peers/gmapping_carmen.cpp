// GMapping (openslam_gmapping GridSlamProcessor) on a CARMEN log, no ROS, no GUI.
//
// symloc's copy of ../shared/peers/gmapping/gmapping_carmen.cpp (the same-run peer harness) with
// one addition: --angleMin and --angleIncrement set the beam geometry of the log (beam i at
// angleMin + i * angleIncrement [rad]), as ROS slam_gmapping passes each scan's own geometry,
// so that GMapping reads 181- and 361-beam logs with the geometry symloc reads them with.
// Default: the harness's -pi/2 + i * pi / n. Built by symloc.bench.peers.gmapping against the
// libraries the harness's build.sh compiles; GMapping itself is not part of symloc.
//
// Input: a CARMEN log with FLASER lines (ODOM and other lines are ignored). For each FLASER the
// pose handed to GMapping is the ODOMETRY pose of the line (odom_x odom_y odom_theta), i.e. the
// perturbed odometry of the comparison (see README.md); the laser sits at the odometry frame's origin.
// Beam i points at -fov/2 + i*fov/n (fov = pi), the convention of GMapping's own CARMEN reader and
// of symloc's reader. Readings >= --nr (no-return marker, default 50 m as in symloc's reader)
// or <= 0 are handed over as "beyond maxRange" so that GMapping skips them.
//
// Parameters: the ROS slam_gmapping defaults (see below), overridable on the command line.
// Output (--out): one line per FLASER: index stamp processed x y theta, where the pose is the best
// particle's (highest accumulated weight at the end) trajectory node for processed scans and, for
// scans GMapping did not process (motion below linearUpdate/angularUpdate), that node of the last
// processed scan composed with the odometry increment since it.
#include <gmapping/gridfastslam/gridslamprocessor.h>
#include <gmapping/utils/stat.h>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>
#include <chrono>
#include <algorithm>

using namespace GMapping;

struct Scan { double stamp; double x, y, th; std::vector<double> r; };

static OrientedPoint compose(const OrientedPoint& a, const OrientedPoint& b) {
  double c = cos(a.theta), s = sin(a.theta);
  return OrientedPoint(a.x + c * b.x - s * b.y, a.y + s * b.x + c * b.y,
                       atan2(sin(a.theta + b.theta), cos(a.theta + b.theta)));
}
static OrientedPoint between(const OrientedPoint& a, const OrientedPoint& b) {  // a^-1 * b
  double c = cos(a.theta), s = sin(a.theta), dx = b.x - a.x, dy = b.y - a.y;
  return OrientedPoint(c * dx + s * dy, -s * dx + c * dy,
                       atan2(sin(b.theta - a.theta), cos(b.theta - a.theta)));
}

int main(int argc, char** argv) {
  std::string in, out;
  int particles = 30; double linearUpdate = 1.0, angularUpdate = 0.5, temporalUpdate = -1.0;
  double srr = 0.1, srt = 0.2, str_ = 0.1, stt = 0.2, sigma = 0.05; int kernelSize = 1;
  double lstep = 0.05, astep = 0.05; int iterations = 5; double lsigma = 0.075, ogain = 3.0;
  int lskip = 0; double minimumScore = 0.0, resampleThreshold = 0.5, delta = 0.05;
  double llsamplerange = 0.01, llsamplestep = 0.01, lasamplerange = 0.005, lasamplestep = 0.005;
  double xmin = -100, ymin = -100, xmax = 100, ymax = 100;
  double maxRange = -1, maxUrange = -1, nr = 50.0, fov = M_PI; unsigned long seed = 0;
  double angleMin = NAN, angleIncrement = NAN;
  for (int i = 1; i < argc; i++) {
    std::string a = argv[i];
    auto nx = [&]() { if (i + 1 >= argc) { std::cerr << "missing value for " << a << "\n"; exit(2);} return std::string(argv[++i]); };
    if (a == "--log") in = nx(); else if (a == "--out") out = nx();
    else if (a == "--particles") particles = atoi(nx().c_str());
    else if (a == "--maxRange") maxRange = atof(nx().c_str());
    else if (a == "--maxUrange") maxUrange = atof(nx().c_str());
    else if (a == "--nr") nr = atof(nx().c_str());
    else if (a == "--seed") seed = strtoul(nx().c_str(), 0, 10);
    else if (a == "--linearUpdate") linearUpdate = atof(nx().c_str());
    else if (a == "--angularUpdate") angularUpdate = atof(nx().c_str());
    else if (a == "--delta") delta = atof(nx().c_str());
    else if (a == "--angleMin") angleMin = atof(nx().c_str());
    else if (a == "--angleIncrement") angleIncrement = atof(nx().c_str());
    else { std::cerr << "unknown option " << a << "\n"; return 2; }
  }
  if (in.empty() || out.empty()) { std::cerr << "usage: gmapping_carmen --log L --out T [--maxRange m] [--maxUrange m] [--nr m] [--seed s] [--angleMin rad] [--angleIncrement rad]\n"; return 2; }
  // no-return marker nr: ROS slam_gmapping uses maxRange = range_max - 0.01 when unset
  if (maxRange < 0) maxRange = nr - 0.01;
  if (maxUrange < 0) maxUrange = maxRange;

  std::vector<Scan> scans;
  {
    std::ifstream f(in.c_str());
    if (!f) { std::cerr << "cannot open " << in << "\n"; return 1; }
    std::string line;
    while (std::getline(f, line)) {
      std::istringstream ss(line); std::string tag; ss >> tag;
      if (tag != "FLASER") continue;
      int n; ss >> n; Scan s; s.r.resize(n);
      for (int k = 0; k < n; k++) ss >> s.r[k];
      double lx, ly, lth; ss >> lx >> ly >> lth >> s.x >> s.y >> s.th >> s.stamp;
      for (int k = 0; k < n; k++) if (!(s.r[k] > 0.0) || s.r[k] >= nr) s.r[k] = maxRange + 1.0;
      scans.push_back(s);
    }
  }
  if (scans.empty()) { std::cerr << "no FLASER lines\n"; return 1; }
  const unsigned nb = scans[0].r.size();
  auto t0 = std::chrono::steady_clock::now();

  GridSlamProcessor* gsp = new GridSlamProcessor(std::cerr);
  if (std::isnan(angleIncrement)) angleIncrement = fov / nb;
  if (std::isnan(angleMin)) angleMin = -0.5 * angleIncrement * nb;
  RangeSensor* laser = new RangeSensor("FLASER", nb, angleIncrement, OrientedPoint(0, 0, 0), 0.0, maxRange);
  for (unsigned k = 0; k < nb; k++)  // the matcher takes its angle table from the beams
    laser->beams()[k].pose.theta = angleMin + k * angleIncrement;
  laser->updateBeamsLookup();
  SensorMap smap; smap.insert(std::make_pair(laser->getName(), laser));
  gsp->setSensorMap(smap);
  gsp->setMatchingParameters(maxUrange, maxRange, sigma, kernelSize, lstep, astep, iterations, lsigma, ogain, lskip);
  gsp->setMotionModelParameters(srr, srt, str_, stt);
  gsp->setUpdateDistances(linearUpdate, angularUpdate, resampleThreshold);
  gsp->setUpdatePeriod(temporalUpdate);
  gsp->setgenerateMap(false);
  OrientedPoint init(scans[0].x, scans[0].y, scans[0].th);
  gsp->GridSlamProcessor::init(particles, xmin + init.x, ymin + init.y, xmax + init.x, ymax + init.y, delta, init);
  gsp->setllsamplerange(llsamplerange); gsp->setllsamplestep(llsamplestep);
  gsp->setlasamplerange(lasamplerange); gsp->setlasamplestep(lasamplestep);
  gsp->setminimumScore(minimumScore);
  GMapping::sampleGaussian(1, seed);

  std::vector<int> processed(scans.size(), 0);
  int nproc = 0;
  for (size_t i = 0; i < scans.size(); i++) {
    const Scan& s = scans[i];
    RangeReading reading(nb, &s.r[0], laser, s.stamp);
    reading.setPose(OrientedPoint(s.x, s.y, s.th));
    if (gsp->processScan(reading)) { processed[i] = 1; nproc++; }
  }
  // best particle's trajectory (tree nodes carry the processed readings, newest first)
  int best = gsp->getBestParticleIndex();
  std::vector<OrientedPoint> nodes;
  for (GridSlamProcessor::TNode* n = gsp->getParticles()[best].node; n; n = n->parent)
    if (n->reading) nodes.push_back(n->pose);
  std::reverse(nodes.begin(), nodes.end());
  auto t1 = std::chrono::steady_clock::now();
  if ((int)nodes.size() != nproc) std::cerr << "warning: " << nodes.size() << " nodes vs " << nproc << " processed scans\n";
  FILE* fo = fopen(out.c_str(), "w");
  fprintf(fo, "# index stamp processed x y theta   (gmapping best particle %d, %d/%zu scans processed, %.3f s)\n",
          best, nproc, scans.size(), std::chrono::duration<double>(t1 - t0).count());
  int k = -1; OrientedPoint last, lastOdo;
  for (size_t i = 0; i < scans.size(); i++) {
    OrientedPoint odo(scans[i].x, scans[i].y, scans[i].th), p;
    if (processed[i] && k + 1 < (int)nodes.size()) { k++; last = nodes[k]; lastOdo = odo; p = last; }
    else p = compose(last, between(lastOdo, odo));
    fprintf(fo, "%zu %.6f %d %.6f %.6f %.6f\n", i, scans[i].stamp, processed[i], p.x, p.y, p.theta);
  }
  fclose(fo);
  std::cout << "scans " << scans.size() << " processed " << nproc << " slam_s "
            << std::chrono::duration<double>(t1 - t0).count() << std::endl;
  return 0;
}
