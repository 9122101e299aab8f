// Driver of the unmodified ROS 1 noetic amcl core (map, pf, sensors) over a symloc
// bench_amcl problem file; mirrors amcl_node.cpp's laserReceived logic. Not part of symloc.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <cstdint>
#include <ctime>
#include <limits>
#include <vector>
#include <utility>
#include <sys/resource.h>

extern "C" {
#include "amcl/map/map.h"
#include "amcl/pf/pf.h"
}
#include "amcl/sensors/amcl_laser.h"
#include "amcl/sensors/amcl_odom.h"

using namespace amcl;

static std::vector<std::pair<int, int>> free_space;

static pf_vector_t uniform_pose(void* arg) {
  map_t* map = (map_t*)arg;
  unsigned idx = drand48() * free_space.size();
  pf_vector_t p;
  p.v[0] = MAP_WXGX(map, free_space[idx].first);
  p.v[1] = MAP_WYGY(map, free_space[idx].second);
  p.v[2] = drand48() * 2 * M_PI - M_PI;
  return p;
}

static double angle_diff(double a, double b) {
  a = atan2(sin(a), cos(a));
  b = atan2(sin(b), cos(b));
  double d1 = a - b, d2 = 2 * M_PI - fabs(d1);
  if (d1 > 0) d2 *= -1.0;
  return fabs(d1) < fabs(d2) ? d1 : d2;
}

static double cpu_now() {
  struct timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

template <class T> static T take(const char*& p) { T v; memcpy(&v, p, sizeof(T)); p += sizeof(T); return v; }

int main(int argc, char** argv) {
  if (argc < 3) { fprintf(stderr, "usage: %s problem seed\n", argv[0]); return 2; }
  srand48(atol(argv[2]));
  double t0 = cpu_now();
  FILE* f = fopen(argv[1], "rb");
  if (!f) { perror(argv[1]); return 1; }
  fseek(f, 0, SEEK_END); long sz = ftell(f); fseek(f, 0, SEEK_SET);
  std::vector<char> buf(sz);
  if (fread(buf.data(), 1, sz, f) != (size_t)sz) return 1;
  fclose(f);
  const char* p = buf.data();
  if (memcmp(p, "SYMLAMC1", 8) != 0) { fprintf(stderr, "not a problem file\n"); return 1; }
  p += 8;
  int w = take<int32_t>(p), h = take<int32_t>(p);
  double res = take<double>(p), ox = take<double>(p), oy = take<double>(p);
  double z_hit = take<double>(p), z_rand = take<double>(p), sigma_hit = take<double>(p),
         max_occ = take<double>(p);
  double a1 = take<double>(p), a2 = take<double>(p), a3 = take<double>(p), a4 = take<double>(p);
  (void)take<double>(p);  // alpha5
  int min_p = take<int32_t>(p), max_p = take<int32_t>(p);
  double pf_err = take<double>(p), pf_z = take<double>(p);
  double a_slow = take<double>(p), a_fast = take<double>(p), d_thresh = take<double>(p),
         a_thresh = take<double>(p);
  int resample_interval = take<int32_t>(p), max_beams = take<int32_t>(p), lm = take<int32_t>(p),
      om = take<int32_t>(p), init = take<int32_t>(p);
  double mean[3], covd[3];
  for (double& v : mean) v = take<double>(p);
  for (double& v : covd) v = take<double>(p);
  int records = take<int32_t>(p);

  map_t* map = map_alloc();
  map->size_x = w; map->size_y = h; map->scale = res;
  map->origin_x = ox + (w / 2) * res;
  map->origin_y = oy + (h / 2) * res;
  map->cells = (map_cell_t*)malloc(sizeof(map_cell_t) * w * h);
  for (int i = 0; i < w * h; i++) map->cells[i].occ_state = (int8_t)p[i];
  p += (size_t)w * h;
  for (int j = 0; j < h; j++)
    for (int i = 0; i < w; i++)
      if (map->cells[MAP_INDEX(map, i, j)].occ_state == -1) free_space.push_back({i, j});

  AMCLLaser* laser = new AMCLLaser(max_beams, map);
  if (lm == 1)
    laser->SetModelLikelihoodFieldProb(z_hit, z_rand, sigma_hit, max_occ, false, 0.5, 0.3, 0.9);
  else
    laser->SetModelLikelihoodField(z_hit, z_rand, sigma_hit, max_occ);
  pf_vector_t lp = pf_vector_zero();
  laser->SetLaserPose(lp);
  AMCLOdom* odom = new AMCLOdom();
  odom->SetModel(om == 1 ? ODOM_MODEL_DIFF_CORRECTED : ODOM_MODEL_DIFF, a1, a2, a3, a4, 0.2);
  double t_map = cpu_now() - t0;

  pf_t* pf = pf_alloc(min_p, max_p, a_slow, a_fast, (pf_init_model_fn_t)uniform_pose, map);
  pf->pop_err = pf_err;
  pf->pop_z = pf_z;
  if (init == 1) {
    pf_init_model(pf, (pf_init_model_fn_t)uniform_pose, map);
  } else {
    pf_vector_t m; m.v[0] = mean[0]; m.v[1] = mean[1]; m.v[2] = mean[2];
    pf_matrix_t c = pf_matrix_zero();
    c.m[0][0] = covd[0]; c.m[1][1] = covd[1]; c.m[2][2] = covd[2];
    pf_init(pf, m, c);
  }

  bool pf_init_ = false;
  pf_vector_t pf_odom_pose = pf_vector_zero();
  int resample_count = 0, n_upd = 0;
  double est[3] = {mean[0], mean[1], mean[2]};
  std::vector<char> out;
  out.reserve(records * 64);
  char line[256];
  double t_upd = 0.0, t_action = 0.0, t_laser = 0.0, t_resample = 0.0, t2 = 0.0;
  for (int k = 0; k < records; k++) {
    pf_vector_t pose;
    pose.v[0] = take<double>(p); pose.v[1] = take<double>(p); pose.v[2] = take<double>(p);
    int n = take<int32_t>(p);
    double angle_min = take<double>(p), angle_inc = take<double>(p), rmin = take<double>(p),
           rmax = take<double>(p);
    const char* ranges = p;
    p += 4 * (size_t)n;
    double t1 = cpu_now();
    bool lupdate = false, force_pub = false;
    pf_vector_t delta = pf_vector_zero();
    if (pf_init_) {
      delta.v[0] = pose.v[0] - pf_odom_pose.v[0];
      delta.v[1] = pose.v[1] - pf_odom_pose.v[1];
      delta.v[2] = angle_diff(pose.v[2], pf_odom_pose.v[2]);
      lupdate = fabs(delta.v[0]) > d_thresh || fabs(delta.v[1]) > d_thresh ||
                fabs(delta.v[2]) > a_thresh;
    }
    if (!pf_init_) {
      pf_odom_pose = pose; pf_init_ = true; lupdate = true; force_pub = true; resample_count = 0;
    } else if (lupdate) {
      AMCLOdomData odata;
      odata.pose = pose;
      odata.delta = delta;
      t2 = cpu_now();
      odom->UpdateAction(pf, (AMCLSensorData*)&odata);
      t_action += cpu_now() - t2;
    }
    bool resampled = false;
    if (lupdate) {
      AMCLLaserData ldata;
      ldata.sensor = laser;
      ldata.range_count = n;
      ldata.range_max = rmax;
      ldata.ranges = new double[n][2];
      for (int i = 0; i < n; i++) {
        float r; memcpy(&r, ranges + 4 * i, 4);
        if (r <= rmin) ldata.ranges[i][0] = ldata.range_max;
        else if (r > ldata.range_max) ldata.ranges[i][0] = std::numeric_limits<double>::max();
        else ldata.ranges[i][0] = r;
        ldata.ranges[i][1] = angle_min + i * angle_inc;
      }
      t2 = cpu_now();
      laser->UpdateSensor(pf, (AMCLSensorData*)&ldata);
      t_laser += cpu_now() - t2;
      pf_odom_pose = pose;
      n_upd++;
      if (!(++resample_count % resample_interval)) {
        t2 = cpu_now();
        pf_update_resample(pf);
        t_resample += cpu_now() - t2;
        resampled = true;
      }
    }
    if (resampled || force_pub) {
      double max_w = 0.0; int best = -1; pf_vector_t bm = pf_vector_zero();
      for (int c = 0; c < pf->sets[pf->current_set].cluster_count; c++) {
        double wgt; pf_vector_t m; pf_matrix_t cv;
        if (!pf_get_cluster_stats(pf, c, &wgt, &m, &cv)) break;
        if (wgt > max_w) { max_w = wgt; best = c; bm = m; }
      }
      if (best >= 0) { est[0] = bm.v[0]; est[1] = bm.v[1]; est[2] = bm.v[2]; }
    }
    t_upd += cpu_now() - t1;
    int len = snprintf(line, sizeof line, "%d %.9f %.9f %.9f %d\n", lupdate ? 1 : 0, est[0],
                       est[1], est[2], pf->sets[pf->current_set].sample_count);
    out.insert(out.end(), line, line + len);
  }
  fwrite(out.data(), 1, out.size(), stdout);
  double hwm = 0.0;
  if (FILE* st = fopen("/proc/self/status", "r")) {
    char l[256];
    while (fgets(l, sizeof l, st)) if (!strncmp(l, "VmHWM:", 6)) hwm = atof(l + 6) / 1024.0;
    fclose(st);
  }
  printf("# updates %d map_cpu %.6f update_cpu %.6f total_cpu %.6f vmhwm_mib %.1f action_cpu %.6f"
         " laser_cpu %.6f resample_cpu %.6f\n", n_upd, t_map, t_upd, cpu_now() - t0, hwm, t_action,
         t_laser, t_resample);
  return 0;
}
