#!/usr/bin/env bash
# Re-assembles the real-photo AprilTag corpus described in datasets/real_photos/MANIFEST.md.
#
#   tools/real_photos.sh OUT_DIR [MIRROR_DIR]
#
# MIRROR_DIR (or the environment variable REAL_PHOTOS_MIRROR when the argument is omitted) is a
# directory holding git copies (bare or not) of the source repositories listed in the manifest, one
# per repository, found as any of
#   MIRROR_DIR/<owner>/<name>.git   MIRROR_DIR/<owner>/<name>   MIRROR_DIR/<owner>+<name>/repo
#   MIRROR_DIR/<owner>+<name>
# They must contain the commits named in the manifest (a clone with full history does). Nothing is
# downloaded. Every file is taken with `git show <commit>:<path>`, checked against the manifest's
# sha256 and written to OUT_DIR/<set>/<name>; the calibration and tag notes of the manifest are
# written next to the photos (calib.yaml, poses.txt, tags.txt). Missing repositories, commits or
# files and checksum mismatches are listed at the end; the exit status is 1 if anything is missing.
set -euo pipefail

usage() { echo "usage: $0 OUT_DIR [MIRROR_DIR]   (or REAL_PHOTOS_MIRROR=MIRROR_DIR $0 OUT_DIR)" >&2; exit 2; }
if [ $# -lt 1 ] || [ $# -gt 2 ]; then usage; fi
out=$1
mirror=${2:-${REAL_PHOTOS_MIRROR:-}}
[ -n "$mirror" ] || usage
[ -d "$mirror" ] || { echo "MIRROR_DIR '$mirror' is not a directory" >&2; exit 2; }
command -v git >/dev/null || { echo "git is required" >&2; exit 2; }
command -v sha256sum >/dev/null || { echo "sha256sum is required" >&2; exit 2; }

git_dir_of() {  # owner/name -> a git dir, or nothing
  local owner=${1%%/*} name=${1#*/} c
  for c in "$mirror/$owner/$name.git" "$mirror/$owner/$name" "$mirror/$owner+$name/repo" "$mirror/$owner+$name"; do
    if [ -d "$c" ] && git --git-dir="$c" rev-parse --git-dir >/dev/null 2>&1; then echo "$c"; return; fi
    if [ -d "$c/.git" ]; then echo "$c/.git"; return; fi
  done
}

missing=()
ok=0
# kind  set  repository  commit  path  name  sha256  bytes
while IFS=$'\t' read -r kind set repo commit path name sum bytes; do
  [ -n "$kind" ] || continue
  gd=$(git_dir_of "$repo")
  if [ -z "$gd" ]; then missing+=("$set/$name: repository $repo not found under MIRROR_DIR"); continue; fi
  if ! git --git-dir="$gd" cat-file -e "$commit^{commit}" 2>/dev/null; then
    missing+=("$set/$name: commit $commit not in $repo"); continue
  fi
  mkdir -p "$out/$set"
  tmp="$out/$set/.$name.part"
  if ! git --git-dir="$gd" show "$commit:$path" >"$tmp" 2>/dev/null; then
    rm -f "$tmp"; missing+=("$set/$name: $repo@$commit has no $path"); continue
  fi
  got=$(sha256sum "$tmp" | cut -d' ' -f1)
  size=$(wc -c <"$tmp")
  if [ "$got" != "$sum" ] || [ "$size" -ne "$bytes" ]; then
    rm -f "$tmp"; missing+=("$set/$name: sha256 $got ($size bytes), manifest says $sum ($bytes bytes) ($repo $path)"); continue
  fi
  mv "$tmp" "$out/$set/$name"
  ok=$((ok + 1))
done <<'TABLE'
photo	duckietown_rotation	duckietown/lib-dt-apriltags	bcf530b9ee566fcc3a6cf33ace96dda191589688	test/test_files/test_image_rotation_-70.png	test_image_rotation_-70.png	af66b6713d14c3c4a15c63701bdc2ebe1e21961d66f2bd4fb642dae30cf740cb	365177
photo	duckietown_rotation	duckietown/lib-dt-apriltags	bcf530b9ee566fcc3a6cf33ace96dda191589688	test/test_files/test_image_rotation_-60.png	test_image_rotation_-60.png	a6f73a256520456957d5d19605d269f4c83c8d31b00fea5b70d294482ea27c59	364592
photo	duckietown_rotation	duckietown/lib-dt-apriltags	bcf530b9ee566fcc3a6cf33ace96dda191589688	test/test_files/test_image_rotation_-50.png	test_image_rotation_-50.png	22a9ddcc98ac7122941bdf00915484bdec1a505c1e3e9477ed59e46a32514b53	364338
photo	duckietown_rotation	duckietown/lib-dt-apriltags	bcf530b9ee566fcc3a6cf33ace96dda191589688	test/test_files/test_image_rotation_-40.png	test_image_rotation_-40.png	8dea2fd25a41f7318850d18a743939ba83e2ea9f434c2d2ab7595360ccbbd2cf	371838
photo	duckietown_rotation	duckietown/lib-dt-apriltags	bcf530b9ee566fcc3a6cf33ace96dda191589688	test/test_files/test_image_rotation_-30.png	test_image_rotation_-30.png	237b22fc4fa1c42f6cbd92439a317a7147c21db4f0e6db7fe3d52b0351a41555	365092
photo	duckietown_rotation	duckietown/lib-dt-apriltags	bcf530b9ee566fcc3a6cf33ace96dda191589688	test/test_files/test_image_rotation_-20.png	test_image_rotation_-20.png	1a268b721e65107f254f0f1f26025fc9cd8f34e66f590b7488de4bece05d09fe	364945
photo	duckietown_rotation	duckietown/lib-dt-apriltags	bcf530b9ee566fcc3a6cf33ace96dda191589688	test/test_files/test_image_rotation_-10.png	test_image_rotation_-10.png	47f2125d6d99776371e4d2b33894fb090f5bc83c818696667aebfd8e678a25d8	364737
photo	duckietown_rotation	duckietown/lib-dt-apriltags	bcf530b9ee566fcc3a6cf33ace96dda191589688	test/test_files/test_image_rotation_0.png	test_image_rotation_0.png	eeb6841b73fa3587504be48e15edf15b7011d49d2213c2ef3211bce06538ecf1	365611
photo	duckietown_rotation	duckietown/lib-dt-apriltags	bcf530b9ee566fcc3a6cf33ace96dda191589688	test/test_files/test_image_rotation_10.png	test_image_rotation_10.png	87559fa4bdd71795de93a8460c4b96fe8a729aa3766dc504d9fe809aafeb01bf	365008
photo	duckietown_rotation	duckietown/lib-dt-apriltags	bcf530b9ee566fcc3a6cf33ace96dda191589688	test/test_files/test_image_rotation_20.png	test_image_rotation_20.png	2c76481347b3a12a76c3f32e4353b26ce0f0e3ec52e98117c00f332e1ec56bf9	362605
photo	duckietown_rotation	duckietown/lib-dt-apriltags	bcf530b9ee566fcc3a6cf33ace96dda191589688	test/test_files/test_image_rotation_30.png	test_image_rotation_30.png	c504d251d6c0d81542482bacced90e08f017d6e698b58afde5175aafdf8be4a9	363872
photo	duckietown_rotation	duckietown/lib-dt-apriltags	bcf530b9ee566fcc3a6cf33ace96dda191589688	test/test_files/test_image_rotation_40.png	test_image_rotation_40.png	52c8c91597c57568505bde0bfb9572c4fe09ff9e69b37e57ad7b29498661db9d	363025
photo	duckietown_rotation	duckietown/lib-dt-apriltags	bcf530b9ee566fcc3a6cf33ace96dda191589688	test/test_files/test_image_rotation_50.png	test_image_rotation_50.png	ad3ea2fd3615207f76813d7ff4b6244fd5fb703dea81a8e4f2a35247ae478374	363287
photo	duckietown_rotation	duckietown/lib-dt-apriltags	bcf530b9ee566fcc3a6cf33ace96dda191589688	test/test_files/test_image_rotation_60.png	test_image_rotation_60.png	2f0669692dc57cedf1d73bd83fc774240c9fbfbfb46e09f66680b91d5e086d88	362579
photo	duckietown_rotation	duckietown/lib-dt-apriltags	bcf530b9ee566fcc3a6cf33ace96dda191589688	test/test_files/test_image_rotation_70.png	test_image_rotation_70.png	6d2ab41d17fc4b5e62e19b631936424df2e4eda66e2038555e31d513ebc8c8f1	362724
photo	duckietown_multiple	duckietown/lib-dt-apriltags	bcf530b9ee566fcc3a6cf33ace96dda191589688	test/test_files/test_image_multiple_01.png	test_image_multiple_01.png	dc1d37967e1e031916147dda288b82042963bc105fbfee688d167072b37874bc	367702
photo	duckietown_multiple	duckietown/lib-dt-apriltags	bcf530b9ee566fcc3a6cf33ace96dda191589688	test/test_files/test_image_multiple_02.png	test_image_multiple_02.png	83a3752d83c2bf8c3377efa9a92d73569e6b0f4533a19069507c2272489aefe8	302373
photo	duckietown_multiple	duckietown/lib-dt-apriltags	bcf530b9ee566fcc3a6cf33ace96dda191589688	test/test_files/test_image_multiple_03.png	test_image_multiple_03.png	67260ddf88fc14b26324bc82fdeb5ac07c8b0124693d1df14734dbee5e2fe84e	333216
photo	duckietown_multiple	duckietown/lib-dt-apriltags	bcf530b9ee566fcc3a6cf33ace96dda191589688	test/test_files/test_image_multiple_04.png	test_image_multiple_04.png	55248b875e7f9aa269ddbf006916585ac7f8dbe2e414a6fde5a8c3f6fa037949	361763
photo	duckietown_multiple	duckietown/lib-dt-apriltags	bcf530b9ee566fcc3a6cf33ace96dda191589688	test/test_files/test_image_multiple_05.png	test_image_multiple_05.png	af6cf7be18b52b56f0b43c6ce00dcc6ffdef742225534b90d65fdb5fad80a95f	321627
photo	duckietown_multiple	duckietown/lib-dt-apriltags	bcf530b9ee566fcc3a6cf33ace96dda191589688	test/test_files/test_image_multiple_06.png	test_image_multiple_06.png	d3ba8f91a03d5b3da142296670c336d25c2d0e9f852e53e1ecb613321bd1d79b	364620
photo	duckietown_multiple	duckietown/lib-dt-apriltags	bcf530b9ee566fcc3a6cf33ace96dda191589688	test/test_files/test_image_multiple_07.png	test_image_multiple_07.png	8f4b86086b1dae5080a2c65bfe56ef1747f09e07884149a94c57d7f14da33440	351741
photo	duckietown_multiple	duckietown/lib-dt-apriltags	bcf530b9ee566fcc3a6cf33ace96dda191589688	test/test_files/test_image_multiple_08.png	test_image_multiple_08.png	5cafe299a9a7892613e4ac5c18c82388d0edec5742bcb433b4678d585b4303db	330632
photo	duckietown_multiple	duckietown/lib-dt-apriltags	bcf530b9ee566fcc3a6cf33ace96dda191589688	test/test_files/test_image_multiple_09.png	test_image_multiple_09.png	cdd8943708b3f2a2973521b875becf49b7d222cf2c3a531fca0be393831c992a	321773
photo	duckietown_multiple	duckietown/lib-dt-apriltags	bcf530b9ee566fcc3a6cf33ace96dda191589688	test/test_files/test_image_multiple_10.png	test_image_multiple_10.png	4da4d7b7cf33d8e95ac8adb22144483fc4b2256d8c891d3eec0cd435bc5a78fa	410558
photo	duckietown_sample	duckietown/lib-dt-apriltags	bcf530b9ee566fcc3a6cf33ace96dda191589688	test/test_files/test_image.png	test_image.png	0d90dd3afb5db6d06a73c5dde39240b6335792e2d1c29328479d9ff3d8f9175c	336230
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1369.JPG	IMG_1369.JPG	2286a0309218d9a8dc658f731b2d3d423ed26abee218d084d184a3022acc59e5	121613
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1371.JPG	IMG_1371.JPG	c5e9d305649ea8f0f7d2ef8b40b7cadb3520895a543e174bb81682ed01acda94	98703
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1373.JPG	IMG_1373.JPG	b271cdc40ca906efebfb138c27386066b0031913695ad51e15ef369fe09968af	105090
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1375.JPG	IMG_1375.JPG	ccb1d88ef89d79b3092143bc6c18a17de0587bd5abca08665d87a197f00e1998	106115
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1377.JPG	IMG_1377.JPG	bb27e3dba76762c77d569334bc80a56c6df5c8514edfbc95e8c08ea4c6c9f9c9	107708
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1379.JPG	IMG_1379.JPG	c591eea75b9048a4f37db8730fed7cfe0d5d4b9f89f2c424ac51e2fbab904130	138323
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1381.JPG	IMG_1381.JPG	edb54fcaa481c9559dcdcb68a45500049b4ef91bf465dbbc31459cbdd4cc73e4	122679
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1383.JPG	IMG_1383.JPG	629f7d160a80f19cf9fcdb8b80e91b03413864f63fc42ee37675c219befc92f5	109362
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1385.JPG	IMG_1385.JPG	00b91e7f7034962934cb2ff1fa0a5af64d6f35afa41a26f70e949a13e5b379fd	107880
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1387.JPG	IMG_1387.JPG	227c7cfbd8daa3b70f92b6bc6c32e18046ec8ed1a771ee9279f6d0ee094b49fa	388310
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1389.JPG	IMG_1389.JPG	188fc26b70d212c83e667475c1287e939b5d3facf5c18fd4281c3ba4d6a2acd7	107602
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1391.JPG	IMG_1391.JPG	0c6ffd4a184c82379790ca680c0c94c523ff03bacbe1812a745efb31a87212da	92726
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1393.JPG	IMG_1393.JPG	5eb9049daf8c3571930dc19cde0e8054b793365ba8c78f14f569abb67040f5c0	88543
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1395.JPG	IMG_1395.JPG	87f3b8d839de3fd5f0ef29e668983faa3bd70a5eaa1bc3b7a19c5288cfc06bcd	100512
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1397.JPG	IMG_1397.JPG	ee5f9bbebff63610c16b130832dede758a07633e2d6ba2cf45d156a051094201	113340
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1399.JPG	IMG_1399.JPG	96f008401c6ed90c9d4ab688da8d58bf11194e37587e3d8daca2d44e127692a8	120710
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1401.JPG	IMG_1401.JPG	adb4556f98e7deddf45c2b07c9d04958d9e99bdca221c656ccd38e40fe842351	119776
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1403.JPG	IMG_1403.JPG	7ceb9f27f647e7e4de278dceace5ca0d70dc0fe1d386321c3061627327fe04f4	124210
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1405.JPG	IMG_1405.JPG	d047be3ed7e9043f6796a9d4c8d9fd88e0f7e713ba4132546fe8172580f5c4a4	117977
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1407.JPG	IMG_1407.JPG	768b3c6e579a1f57d04333ffcaf4d58ebb40f0839773feddd92b8ca16c9d67c4	113753
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1409.JPG	IMG_1409.JPG	dfc8b6394f307568ad551d0a3726298721bcee9e93e564e255a8747e499fe6a9	94769
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1410.JPG	IMG_1410.JPG	bcc2e60dd31f4f89d7cae538569bd37cfc0799b4c33e2c0b63087ac2d11d3d08	120687
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1411.JPG	IMG_1411.JPG	946c5b7e03e173484fecaeaa854c5b96aee7b417a9782a06b5162f9737e00e79	105735
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1412.JPG	IMG_1412.JPG	76a11bcb7e5771833b22666b6cba6da44bd1d182a7a47fffe7d6c7a111c8824a	104356
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1413.JPG	IMG_1413.JPG	a9f0454a3bb2af3257312fe22b27c3065d77e86d0c835f3018b6bb28cb6531cb	107075
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1414.JPG	IMG_1414.JPG	7cd99897934cc2f5b6433cef2ebbf8f3cf5cbed1b9ce2439de1760d00b009cda	119360
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1415.JPG	IMG_1415.JPG	3117be21200189541dba6a0a6c9857e9b1d06016ecfdadeb1bc036b092ade0a3	126461
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1416.JPG	IMG_1416.JPG	0309337974d75a676495373eeb9dbaf12a521837f1e0bd611ecde45efd4caeff	136430
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1417.JPG	IMG_1417.JPG	ed8422050e397ba407e581e793bf8761097034ee808c12cd0fd9bdd8a340e76e	116564
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1418.JPG	IMG_1418.JPG	5ccb0ef2b450f7bae99a9ad26290de102b5c34468185956d215cb9076a64a2d8	106134
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1419.JPG	IMG_1419.JPG	780fcd3c8ede854c68d93af40286af1da5766783e5b29385e1ddd855a0513723	96703
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1420.JPG	IMG_1420.JPG	a6f3805cf66388d84cc54e7cca31f3249b36580648cdf4ccddf86f620deb371b	100763
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1421.JPG	IMG_1421.JPG	e5240e9ac2e78fbcda5261cd2c2001e75dab6c54634847c6d5576cfe0ce8d68c	99265
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1422.JPG	IMG_1422.JPG	fecaddbc490df9f5a2a0dd5001056afd790a21c4dc14627d37795cde6ed019ec	91404
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1423.JPG	IMG_1423.JPG	d6037042f29006d00383e8737ff03ee528b22f7fa6fc8c0191f2b9a5f364e580	101830
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1424.JPG	IMG_1424.JPG	695c8c218293964f70cf8b21d6afd6c180269da63df5f1949b220af2fa13ae17	101354
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1425.JPG	IMG_1425.JPG	b83718f61a00cf92b233edf12bb018701a13ca0a3c999fed1166de77d73e4a94	105511
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1426.JPG	IMG_1426.JPG	fca9ed3d25b7a8b29f256eeed6539f1c247a2f045a790bd888e26a681ae68c0d	124672
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1427.JPG	IMG_1427.JPG	919ab8a8bc143b773123cb1a1a2a5b303da52f07b36701acbe2365b47a834e39	120754
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1428.JPG	IMG_1428.JPG	c189b1b12d12f3f756614057926e55f1732dbc0a7261a840a24b16f8b1878880	119230
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1429.JPG	IMG_1429.JPG	c838e88d1b2eb49993189069f47867d203cffdbabd2fe301780991210a3e6170	133112
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1430.JPG	IMG_1430.JPG	81215309cfdd1c5bc6cf797cbb07cbb9f6498f468c5ce2eee0dd79fd86b7c4c8	126995
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1431.JPG	IMG_1431.JPG	906324670c33e83671fe96792f105c4bc0f66306bceb9ab09a448af5b8c45192	103730
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1450.JPG	IMG_1450.JPG	dcf070bff60c88fc4a4d23a11c1198ad8b062f0c3c13300f7213a6ed6cb4029e	120333
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1451.JPG	IMG_1451.JPG	4613c0e6c5a4d9af2bff0cbda7c215c0793dd30b0141f05c00245fba98c5b6f6	113974
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1452.JPG	IMG_1452.JPG	50c9c1da71b996482c78d81515e1ec6588eb3b1ea8de6ee827a9fed26c0c1280	118627
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1453.JPG	IMG_1453.JPG	182a11a89d6f3f3693d248551febe915df557779a72c47affb6506a937df08e6	142162
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1454.JPG	IMG_1454.JPG	ed6ba9e218f7287285bacc45190ee9a00704e975c94bcfea0841e823e4942843	126429
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1455.JPG	IMG_1455.JPG	3534c8623a1e9433e865389e79c974fcf507f1d05bad4e9a6493ae357991ea3f	139861
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1457.JPG	IMG_1457.JPG	98539e6da299d798a02573c41d2343449c826f69915c702dc1feac7f99749494	114252
photo	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/IMG_1458.JPG	IMG_1458.JPG	2ca0011ad8a95314f839c909ba2cada45d97e496e8f4e5dd9cd6f789d1391330	124773
photo	swatbotics_hallway	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/hallway/IMG_0612.jpg	IMG_0612.jpg	19df6f1a8421423935730e22c5ef4a81fdd9fdd09c073c2d669c7c86342a60ac	159834
photo	swatbotics_hallway	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/hallway/IMG_0613.jpg	IMG_0613.jpg	b342c037d87786b6ef9ec2bc8fd9113021b8e825fc16940466555e4807e5aedb	146842
photo	swatbotics_hallway	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/hallway/IMG_0614.jpg	IMG_0614.jpg	a7204d23834677e4acaf4b820d7a0fe4f2aefeb617ee3978afa5a55d585dfe75	168108
photo	swatbotics_hallway	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/hallway/IMG_0615.jpg	IMG_0615.jpg	2222d34aba1aa2371b816a5bab669750d3607e00b02bee6f9a43913a98ad8689	152063
photo	swatbotics_hallway	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/hallway/IMG_0617.jpg	IMG_0617.jpg	ce3114c47cc036190fb2dbc182f44de059be2f33c41696a480395742bbb00a52	161062
photo	swatbotics_clipboard	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/clipboard/clipboard00.png	clipboard00.png	28d0e0f65392335bf986f3dc3ab18301ac3bb6934be5d76b7a1c3ec4f7abbd6c	132198
photo	swatbotics_clipboard	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/clipboard/clipboard01.png	clipboard01.png	1cf6455917b79d07ed190de2318c463b0ee0e45348687bcdc6ec8ee50a0fc4c4	138937
photo	swatbotics_clipboard	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/clipboard/clipboard02.png	clipboard02.png	c38bc8280854b6afea53389c6c259d73cb688a42e896a69a71c0bd0be64d09dd	136198
photo	swatbotics_clipboard	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/clipboard/clipboard03.png	clipboard03.png	53f625568863b450e859e6f3f35a342697aa7be0d6d31165fcbb768bfe99217b	113434
photo	swatbotics_clipboard	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/clipboard/clipboard04.png	clipboard04.png	cc00ca5e2b54e86f49468bfa0d0d2aa4120479ae638d1a8eb8dde101e8871ba0	124388
photo	swatbotics_clipboard	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/clipboard/clipboard05.png	clipboard05.png	5eea487bb2ae09bde833b805616f462bbf63c5a957707ec28f51cb901e269c52	133513
photo	swatbotics_clipboard	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/clipboard/clipboard06.png	clipboard06.png	79138122686f6bb1ec5db00f39d8aacf6f726c489728aadfe6e981aa09e0b746	142257
photo	swatbotics_clipboard	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/clipboard/clipboard07.png	clipboard07.png	06523524602b36b1e6c5351bc6ffa2653ecea8453c78d42df7bf6271c153b28f	134862
photo	swatbotics_clipboard	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/clipboard/clipboard08.png	clipboard08.png	84ef2f5c24080ded24fc325fe44f56776ce64c8ebb4c58ef34137b7d13ffabb0	119488
photo	swatbotics_clipboard	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/clipboard/clipboard09.png	clipboard09.png	34974cb597bbfeb9465e524c0586ae95bfda3cc43a76225cf0e8512731e4ffe9	137964
photo	kornia_board	kornia/kornia-rs	f3070712b4938010eb7b32fa263e2d45d39e622a	tests/data/apriltag_board_multicam/camera_0.jpg	camera_0.jpg	7abe194030ecda0e63bc6ba14d5101963aa587ee82a3491ea9b50530e530fffc	360078
photo	kornia_board	kornia/kornia-rs	f3070712b4938010eb7b32fa263e2d45d39e622a	tests/data/apriltag_board_multicam/camera_1.jpg	camera_1.jpg	1a7d18d938ce5e79ffc7942500a51211a35c386c18a0fb16580615bffd2bb5a4	351963
photo	juliarobotics	JuliaRobotics/AprilTags.jl	e26240a2454477f93b18fe2bc6e253d0adbefc77	data/tagtest.jpg	tagtest.jpg	0a9ffba6be87f91e12dd9bb2ae148cf0479f931da090d49fb089ee62a1213831	66933
photo	juliarobotics	JuliaRobotics/AprilTags.jl	e26240a2454477f93b18fe2bc6e253d0adbefc77	data/colortag.jpg	colortag.jpg	ac5858e5fa3017adaaed2ffce7340bba56661c9cebd4ee0ca06aa097ed66c383	15324
photo	wpilib	wpilibsuite/allwpilib	caf0fb2dccb462a1507888246646daa5ba38cd82	apriltag/src/test/python/tag1_640_480.jpg	tag1_640_480.jpg	a8856a596fd26ecd2dea848604aa6b15508c75d49839a818c3f4068a80d36591	26688
aux	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/groundtruth.txt	groundtruth.txt	f6a326f7501b0118432a95d44a42935fef495da40c2e3b2776636407b27e7695	1530
aux	swatbotics_mapping	swatbotics/apriltag	427a42ce24578e0fcc483eaf35794b986352070d	images/mapping_feb_2014/calibration/calib.txt	calib_source.txt	e647a842c18f2c9ac2e36f80ad2a90e6c349eaa954f29167116fff9e04753a2d	200
aux	duckietown_rotation	duckietown/lib-dt-apriltags	bcf530b9ee566fcc3a6cf33ace96dda191589688	test/test_files/test_info.yaml	test_info.yaml	19d138475a46c7b53130c1cbc4ef0b8706c52647ffab7395d4a0a7f92a3d9968	1443
aux	duckietown_multiple	duckietown/lib-dt-apriltags	bcf530b9ee566fcc3a6cf33ace96dda191589688	test/test_files/test_info.yaml	test_info.yaml	19d138475a46c7b53130c1cbc4ef0b8706c52647ffab7395d4a0a7f92a3d9968	1443
aux	duckietown_sample	duckietown/lib-dt-apriltags	bcf530b9ee566fcc3a6cf33ace96dda191589688	test/test_files/test_info.yaml	test_info.yaml	19d138475a46c7b53130c1cbc4ef0b8706c52647ffab7395d4a0a7f92a3d9968	1443
TABLE

write_note() {  # set file: writes stdin to OUT_DIR/set/file if the set exists
  if [ -d "$out/$1" ]; then cat >"$out/$1/$2"; else cat >/dev/null; fi
}

calib() {  # set width height fx fy cx cy
  write_note "$1" calib.yaml <<YAML
%YAML:1.0
---
image_width: $2
image_height: $3
camera_matrix: !!opencv-matrix
   rows: 3
   cols: 3
   dt: d
   data: [ $4, 0., $6, 0., $5, $7, 0., 0., 1. ]
distortion_coefficients: !!opencv-matrix
   rows: 1
   cols: 5
   dt: d
   data: [ 0., 0., 0., 0., 0. ]
YAML
}

# Camera matrices as stated by the source repositories (see MANIFEST.md); no distortion is stated
# for any of them (the Duckietown photos are already rectified), hence the zero coefficients.
calib duckietown_rotation 1056 792 329.8729619143081 332.94611303946357 528.0 396.0
calib duckietown_multiple 640 480 338.563277422543 338.939280638548 336.45495347495824 230.486982216255
calib duckietown_sample 640 480 336.7755634193813 336.02729840829176 333.3575643300718 212.77376312080065
calib swatbotics_mapping 816 612 765.00 764.18 393.72 304.66

write_note duckietown_rotation poses.txt <<'TXT'
Source: duckietown/lib-dt-apriltags test/test_files/test_info.yaml (copied here as test_info.yaml), entry rotation_test.
tag family tag36h11, id 76, tag_size 0.065 m (black square side, as libapriltag's tag size)
stated pose of the tag: posx 0.30, posy 0.00, posz 0.05 (m), rotx 0.0, roty 0.0, rotz variable
rotz is the angle in each file name (test_image_rotation_<deg>.png, -70..70 degrees); the frame of
posx/posy/posz/rot* is not defined in the source (a Duckiebot-style frame is likely: x forward).
The camera matrix in calib.yaml is the one stated for these (rectified) images.
TXT
write_note duckietown_multiple tags.txt <<'TXT'
Source: duckietown/lib-dt-apriltags test/test_files/test_info.yaml, entry multiple_tags_test.
tag family tag36h11, tag_size 0.065 m; camera matrix in calib.yaml as stated there; images rectified.
TXT
write_note duckietown_sample tags.txt <<'TXT'
Source: duckietown/lib-dt-apriltags test/test_files/test_info.yaml, entry sample_test.
tag family tag36h11, tag_size 0.065 m; camera matrix in calib.yaml as stated there; image rectified.
TXT
write_note swatbotics_mapping tags.txt <<'TXT'
Source: swatbotics/apriltag images/mapping_feb_2014 (iPhone 4S, 816x612).
tag family tag36h11, ids 0-19 printed on letter paper and taped to the walls of one room.
tag size 0.127 m: the value the repository README passes (-s .127) to its pose example on these
images; not otherwise stated. groundtruth.txt (copied from the repository) lists the ids visible in
each image, including images not in this corpus. calib_source.txt is the repository's calibration
note: fx fy cx cy only, no distortion (calib.yaml carries zeros).
TXT
write_note kornia_board tags.txt <<'TXT'
Source: kornia/kornia-rs examples/apriltag_board_multicam/src/main.rs at the manifest's commit.
tag family tag36h11, one 6x6 board ("MakerWorld 6x6 AprilTag board"), ids by row from the top:
35 34 33 32 31 30 / 29 28 27 26 25 24 / 23 22 21 20 19 18 / 17 16 15 14 13 12 / 11 10 9 8 7 6 / 5 4 3 2 1 0
tag size 0.0256 m, pitch 0.032 m (printed 16 mm / 20 mm scaled by 1.6, as the example's constants
state). No camera calibration is given (the example estimates intrinsics from the board).
TXT

echo "real_photos: $ok files written to $out"
if [ ${#missing[@]} -gt 0 ]; then
  echo "MISSING (${#missing[@]}):" >&2
  printf '  %s\n' "${missing[@]}" >&2
  exit 1
fi
