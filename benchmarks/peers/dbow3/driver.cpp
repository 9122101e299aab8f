// Peer of benchmarks/bench_vision.py: DBoW3's BoW transform on the same vocabulary and
// descriptors as symloc, timed in the same way (median CPU time per transform).
//
// usage: dbow3_driver VOCABULARY_TXT DESCRIPTORS_BIN REPEATS OUT_TXT
//   VOCABULARY_TXT   DBoW2 text vocabulary (symloc: Vocabulary.save_dbow2_text), a name
//                    ending in .txt: DBoW3::Vocabulary::load reads it with load_fromtxt
//                    (which keeps the weights as float)
//   DESCRIPTORS_BIN  int32 image count, then per image int32 N and N x 32 bytes (ORB)
//   REPEATS          timed transforms per image
//   OUT_TXT          per image one line: the BoW vector as "word:value ..." (%.17g)
// prints: "load_ms <CPU ms>" and "transform_ms <median CPU ms over all timed transforms>"
#include <time.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <vector>

#include "DBoW3.h"

static double cpu_ms() {
  timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return 1e3 * t.tv_sec + 1e-6 * t.tv_nsec;
}

int main(int argc, char** argv) {
  if (argc != 5) {
    std::cerr << "usage: dbow3_driver VOCABULARY_TXT DESCRIPTORS_BIN REPEATS OUT_TXT\n";
    return 2;
  }
  const int repeats = std::atoi(argv[3]);
  DBoW3::Vocabulary voc;
  double t0 = cpu_ms();
  voc.load(argv[1]);
  const double load_ms = cpu_ms() - t0;
  std::ifstream in(argv[2], std::ios::binary);
  int32_t n_images = 0;
  in.read(reinterpret_cast<char*>(&n_images), 4);
  std::vector<cv::Mat> images;
  for (int i = 0; i < n_images; ++i) {
    int32_t n = 0;
    in.read(reinterpret_cast<char*>(&n), 4);
    cv::Mat d(n, 32, CV_8UC1);
    in.read(reinterpret_cast<char*>(d.data), static_cast<std::streamsize>(n) * 32);
    images.push_back(d);
  }
  if (!in) {
    std::cerr << "dbow3_driver: " << argv[2] << ": truncated descriptor file\n";
    return 1;
  }
  std::vector<double> times;
  FILE* out = std::fopen(argv[4], "w");
  for (const cv::Mat& d : images) {
    DBoW3::BowVector v;
    voc.transform(d, v);  // warm-up
    for (int r = 0; r < repeats; ++r) {
      DBoW3::BowVector w;
      const double c0 = cpu_ms();
      voc.transform(d, w);
      times.push_back(cpu_ms() - c0);
    }
    for (const auto& kv : v) std::fprintf(out, "%u:%.17g ", kv.first, kv.second);
    std::fprintf(out, "\n");
  }
  std::fclose(out);
  std::sort(times.begin(), times.end());
  const double median = times.empty() ? 0.0 : times[times.size() / 2];
  std::printf("load_ms %.3f\ntransform_ms %.4f\n", load_ms, median);
  return 0;
}
