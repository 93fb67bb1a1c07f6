#!/usr/bin/env python3
# Issue 15: the single-IMU monitors on log171 damaged as a board damages it
# (replay 80-235 s, each IMU alone): the IMU rows of a spell cut (dropout)
# or held at its first row (frozen), the attitude or GNSS velocity rows of a
# spell cut or held at its first (a source repeating its last output);
# onsets 120/150/180/210 s. Prints, per damage and spell (onset+duration),
# the flag events beyond the undamaged run's, summed over the three IMUs.
# usage: scripts/single-imu-damaged.py BIN ukf|otsukf
#   KINDS (env, comma-separated; default all): imu cut, imu frozen, att cut,
#   gps cut, att frozen, gps frozen
#   (BIN: e.g. target/release/imu-fdi-sim, built with
#    `cargo build --release -p imu-fdi-cli --bin imu-fdi-sim`)
import csv, json, os, subprocess, sys, tempfile
if len(sys.argv) != 3 or sys.argv[2] not in ('ukf', 'otsukf'):
    sys.exit('usage: single-imu-damaged.py BIN ukf|otsukf')
B=sys.argv[1]; mon=sys.argv[2]
D=os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'tests', 'data')
TMP=tempfile.mkdtemp()
def load(f):
    rows=list(csv.reader(open(f))); return rows[0],rows[1:]
ih,idat=load(D+'/ap_log171_3imu.csv'); gh,gdat=load(D+'/ap_log171_gps_vel_ned.csv'); ah,adat=load(D+'/ap_log171_attitude_quat.csv')
def write(fn,h,d):
    with open(fn,'w',newline='') as f:
        w=csv.writer(f); w.writerow(h); w.writerows(d)
def run(imu=None, gps=None, att=None):
    fi,fg,fa=[os.path.join(TMP, n+'.csv') for n in ('imu','gnss','att')]
    write(fi,ih,imu or idat); write(fg,gh,gps or gdat); write(fa,ah,att or adat)
    p=subprocess.run([B,'replay',fi,'--gnss',fg,'--att',fa,'--from','80','--to','235','--monitor',mon,'--json'],capture_output=True,text=True)
    if p.returncode:
        sys.exit(p.stderr.strip())
    j=json.loads(p.stdout)
    return [[c['flag_events'] for c in j['channels'][6*k:6*k+6]] for k in range(j['imus'])]
base=run()
def extra(ev):
    if ev is None: return 'ERR'
    return sum(max(0,e-b) for E,Bs in zip(ev,base) for e,b in zip(E,Bs))
def frz(lo,hi,dat=None):
    out=[];held=None
    for r in (idat if dat is None else dat):
        r=list(r)
        if lo<=float(r[0])<hi:
            if held is None: held=r[1:]
            r[1:]=held
        out.append(r)
    return out
tot={}
KINDS=os.environ.get('KINDS','imu cut,imu frozen,att cut,gps cut,att frozen,gps frozen').split(',')
for kind in KINDS:
    cells=[]
    for t0 in [120,150,180,210]:
        for dur in ([0.5,2,5] if kind.startswith('imu') else [2,10,30]):
            lo,hi=t0,t0+dur
            if kind=='imu cut': ev=run(imu=[r for r in idat if not lo<=float(r[0])<hi])
            elif kind=='imu frozen': ev=run(imu=frz(lo,hi))
            elif kind=='att cut': ev=run(att=[r for r in adat if not lo<=float(r[0])<hi])
            elif kind=='att frozen': ev=run(att=frz(lo,hi,adat))
            elif kind=='gps frozen': ev=run(gps=frz(lo,hi,gdat))
            else: ev=run(gps=[r for r in gdat if not lo<=float(r[0])<hi])
            x=extra(ev); cells.append(f"{t0}+{dur}:{x}")
            tot[kind]=tot.get(kind,0)+(x if isinstance(x,int) else 0)
    print(f"{mon} {kind:11s} extra events (3 IMUs): total {tot[kind]:3d} | "+' '.join(cells))
